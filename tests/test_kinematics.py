"""Free-space driving follows the exact arc of the wheel command."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot, wheels

TRACK = 0.3


def exact_arc(start: np.ndarray, v: float, omega: float, t: float) -> np.ndarray:
    x, y, theta = start
    if abs(omega) < 1e-12:
        return np.array([x + v * t * math.cos(theta), y + v * t * math.sin(theta), theta])
    radius = v / omega
    end = theta + omega * t
    return np.array([x + radius * (math.sin(end) - math.sin(theta)),
                     y - radius * (math.cos(end) - math.cos(theta)), end])


@pytest.mark.parametrize("left,right", [
    (0.5, 0.5),     # straight
    (-0.4, 0.4),    # spin in place
    (0.3, 0.7),     # left arc
    (1.0, 0.2),     # tight right arc
    (-0.6, -0.5),   # reversing arc
])
def test_free_space_motion_follows_exact_arc(make_sim, left, right):
    sim = make_sim([robot([10, 10, 0.3], controller=wheels(left, right))], size=(20, 20))
    sim.run(1.0)  # past the acceleration ramp
    r = sim.robots["r"]
    start = r.pose
    sim.run(10.0)
    v, omega = (left + right) / 2, (right - left) / TRACK
    expected = exact_arc(start, v, omega, 10.0)
    assert np.hypot(*(r.pose[:2] - expected[:2])) < 1e-3  # [m]
    assert abs(r.pose[2] - expected[2]) < 1e-6


def test_speed_and_acceleration_limits(make_sim):
    sim = make_sim([robot([2, 10, 0], max_wheel_speed=0.8, max_accel=2.0,
                          controller=wheels(3.0, 3.0))])
    r = sim.robots["r"]
    sim.run(0.2)
    assert r.velocity[0] == pytest.approx(2.0 * 0.2, abs=2.0 / 60 + 1e-9)  # ramping at max_accel
    sim.run(1.0)
    assert r.velocity[0] == pytest.approx(0.8, abs=1e-9)  # clamped to max wheel speed


def test_clamping_keeps_the_turn_radius(make_sim):
    """Over-fast wheel commands are scaled together, so the robot still drives the same curve."""
    sim = make_sim([robot([10, 10, 0], controller=wheels(1.0, 3.0))])
    sim.run(2.0)
    left, right = sim.robots["r"].drive.wheel_speeds
    assert right == pytest.approx(1.0)
    assert left == pytest.approx(1.0 / 3.0)


def test_set_wheel_speeds_overrides_the_controller_until_cleared(make_sim):
    sim = make_sim([robot([10, 10, 0], controller=wheels(0.5, 0.5))])
    r = sim.robots["r"]
    r.set_wheel_speeds(0.0, 0.0)
    sim.run(1.0)
    assert np.allclose(r.pose, [10, 10, 0])
    r.clear_wheel_speeds()
    sim.run(1.0)
    assert r.pose[0] > 10.2


def test_time_is_exact_step_count(make_sim):
    sim = make_sim([robot([1, 1, 0])], dt=0.01)
    sim.run(2.5)
    assert sim.steps == 250
    assert sim.time == pytest.approx(2.5, abs=1e-12)
