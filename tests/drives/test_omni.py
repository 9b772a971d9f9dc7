"""The omnidirectional drive: exact sideways motion, limits, walls, crates, wheel odometry."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot

from test_ackermann import fit_circle

OMNI = {"drive": "omni", "max_speed": 1.0, "max_angular_speed": 2.0, "max_accel": 3.0}


def test_moves_sideways_exactly(make_sim):
    sim = make_sim([robot([5, 5, 0.7], name="holo", **OMNI)])
    holo = sim.robots["holo"]
    holo.set_velocity(0.0, 0.0, vy=0.6)
    sim.run(1.0)
    start = holo.pose.copy()
    sim.run(2.0)
    moved = holo.pose - start
    # 1.2 m to the robot's left, nothing forward, heading unchanged.
    assert moved[0] == pytest.approx(-1.2 * math.sin(0.7), abs=1e-9)
    assert moved[1] == pytest.approx(1.2 * math.cos(0.7), abs=1e-9)
    assert moved[2] == pytest.approx(0.0, abs=1e-12)
    assert holo.drive.twist == pytest.approx((0.0, 0.6, 0.0))


def test_translating_while_turning_is_an_exact_circle(make_sim):
    sim = make_sim([robot([10, 10, 0], name="holo", **OMNI)])
    holo = sim.robots["holo"]
    holo.set_velocity(0.3, 0.5, vy=0.4)  # |v| = 0.5 m/s at 0.5 rad/s: a 1 m circle
    sim.run(2.0)
    points = []
    for _ in range(120):
        sim.step()
        points.append(holo.pose[:2].copy())
    _, radius = fit_circle(np.array(points))
    assert radius == pytest.approx(1.0, abs=1e-6)


def test_speed_limit_is_on_the_norm(make_sim):
    sim = make_sim([robot([5, 5, 0], name="holo", **OMNI)])
    holo = sim.robots["holo"]
    holo.set_velocity(2.0, 5.0, vy=2.0)
    command = holo.drive.command
    assert math.hypot(command.v, command.vy) == pytest.approx(1.0)
    assert command.v == pytest.approx(command.vy)
    assert command.omega == pytest.approx(2.0)


@pytest.mark.parametrize("heading", [0.0, math.pi / 2])
def test_stops_at_a_wall_sliding_sideways(make_sim, heading):
    sim = make_sim([robot([2, 2, heading], name="holo", **OMNI,
                          footprint={"type": "box", "size": [0.4, 0.3]})], size=(4.0, 4.0))
    holo = sim.robots["holo"]
    # Slide toward +x in the world: sideways (-vy) when facing +y, forward when facing +x.
    holo.set_velocity(*((1.0, 0.0, 0.0) if heading == 0.0 else (0.0, 0.0, -1.0)))
    sim.run(3.0)
    right = max(s.bb.right for s in holo.shapes)
    assert 4.0 - 0.002 <= right <= 4.0 + 0.01
    assert holo.collisions == 1


def test_pushes_a_crate_sideways(make_sim):
    sim = make_sim([robot([2, 1, math.pi / 2], name="holo", **OMNI)],
                   [{"type": "box", "center": [2.0, 2.0], "size": [0.4, 0.4], "movable": True}],
                   size=(4.0, 6.0))
    holo = sim.robots["holo"]
    holo.set_velocity(0.6, 0.0)  # facing +y: forward pushes the crate up
    sim.run(4.0)
    assert sim.world.obstacles[0].body.position.y > 3.0


@pytest.mark.parametrize("wheels", ["mecanum", "omni3"])
def test_noise_free_wheel_odometry_follows_the_truth(make_sim, wheels):
    sim = make_sim([robot([5, 5, 0.2], name="holo", **OMNI, wheels=wheels)])
    holo = sim.robots["holo"]
    holo.set_velocity(0.4, 0.6, vy=-0.3)
    sim.run(4.0)
    assert np.allclose(holo.odometry.pose, holo.pose, atol=1e-6)
    assert len(holo.odometry.wheel_travel) == 4


def test_wheel_errors_make_odometry_drift_and_covariance_grow(make_sim):
    odometry = {"scale_errors": [0.02, -0.02, 0.0, 0.0], "wheel_noise_std": 0.01}
    sim = make_sim([robot([5, 5, 0.0], name="holo", **OMNI, odometry=odometry)], seed=2)
    holo = sim.robots["holo"]
    holo.set_velocity(0.0, 0.0, vy=0.5)
    sim.run(4.0)
    error = math.hypot(*(holo.odometry.pose[:2] - holo.pose[:2]))
    assert 0.005 < error < 0.2
    assert np.trace(holo.odometry.covariance) > 0


def test_controllers_use_the_sideways_freedom(make_sim):
    sim = make_sim([robot([2, 2, 0], name="holo", **OMNI, goal={"position": [2, 6]},
                          controller={"type": "go_to_goal"})], size=(4.0, 8.0))
    sim.step()
    holo = sim.robots["holo"]
    assert holo.drive.command.vy > 0.95  # slides toward the goal on its left
    off_line = 0.0
    for _ in range(round(8.0 / sim.dt)):
        sim.step()
        off_line = max(off_line, abs(holo.pose[0] - 2.0))
    assert holo.goal_reached
    assert off_line < 0.06  # near a straight line while it turns 90 deg to face the goal
