"""Wheel odometry: exact without noise, the configured systematic errors, quantisation, slip."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot, wheels

from pymunk_bot.geometry.arcs import sinc_half

TRACK = 0.3  # [m], the robot default


def pose_error(r) -> tuple[float, float]:
    """(position error [m], heading error [rad]) of odometry against ground truth."""
    e = r.odometry.pose - r.pose
    return math.hypot(e[0], e[1]), abs(e[2])


def drive_program(sim, r, program: str, rng: np.random.Generator) -> None:
    """Set the wheel command for the next stretch of a named driving program."""
    if program == "random":  # a new command every 0.1 s, like a 10 Hz controller
        r.set_wheel_speeds(*rng.uniform(-1.0, 1.0, 2))
    elif program == "spin_then_drive":
        r.set_wheel_speeds(*((-0.6, 0.6) if int(sim.time) % 4 == 0 else (0.8, 0.9)))


@pytest.mark.parametrize("substeps", [1, 4])
@pytest.mark.parametrize("program,command", [
    ("const", (1.0, 1.0)),      # straight
    ("const", (0.4, 0.8)),      # arc
    ("const", (-0.7, -0.5)),    # reversing arc
    ("spin_then_drive", None),  # spins in place between arcs
    ("random", None),
])
def test_noise_free_odometry_matches_ground_truth_over_10_m(make_sim, substeps, program, command):
    sim = make_sim([robot([10, 10, 0.4], controller=wheels(*(command or (0, 0))))], substeps=substeps)
    r = sim.robots["r"]
    assert np.array_equal(r.odometry.pose, r.pose)  # starts at the true start pose
    rng = np.random.default_rng(3)
    worst_position = worst_heading = 0.0
    while r.distance < 10.0:
        if sim.steps % 6 == 0:
            drive_program(sim, r, program, rng)
        sim.step()
        position, heading = pose_error(r)
        worst_position = max(worst_position, position)
        worst_heading = max(worst_heading, heading)
    assert worst_position < 1e-3  # [m]
    assert worst_heading < 1e-4  # [rad]


def test_wheel_radius_and_track_errors_bend_a_straight_drive_by_the_predicted_arc(make_sim):
    errors = {"left_scale_error": 0.01, "right_scale_error": -0.005, "track_width_error": 0.04}
    sim = make_sim([robot([2, 10, 0.0], odometry=errors, controller=wheels(1.0, 1.0))])
    r = sim.robots["r"]
    sim.run(12.0)
    travel = r.distance  # both wheels travelled this far (a straight line in free space)
    assert r.pose[1] == pytest.approx(10.0, abs=1e-9)
    # The robot believes each wheel went travel * (1 + e): one arc of constant curvature.
    left = travel * (1 + errors["left_scale_error"])
    right = travel * (1 + errors["right_scale_error"])
    turn = (right - left) / (TRACK * (1 + errors["track_width_error"]))
    chord = 0.5 * (left + right) * sinc_half(turn)
    expected = np.array([2 + chord * math.cos(turn / 2), 10 + chord * math.sin(turn / 2), turn])
    assert np.allclose(r.odometry.pose, expected, atol=1e-6)
    assert r.odometry.pose[1] < 10.0 - 0.01  # the right wheel reads short: it believes it veered right


def test_track_width_error_scales_the_believed_turn(make_sim):
    sim = make_sim([robot([5, 5, 0.0], odometry={"track_width_error": 0.1},
                          controller=wheels(-0.5, 0.5))])
    r = sim.robots["r"]
    sim.run(5.0)
    assert r.pose[2] > 10.0  # more than one and a half turns
    assert r.odometry.pose[2] == pytest.approx(r.pose[2] / 1.1, rel=1e-9)
    assert np.allclose(r.odometry.pose[:2], r.pose[:2], atol=1e-9)  # a spin stays in place


def test_encoder_resolution_quantises_the_travel(make_sim):
    resolution = 0.013  # [m] per encoder tick
    sim = make_sim([robot([2, 10, 0.0], odometry={"encoder_resolution": resolution},
                          controller=wheels(1.0, 1.0))])
    r = sim.robots["r"]
    reported = set()
    for _ in range(300):
        sim.step()
        left, right = r.odometry.wheel_travel
        ticks = left / resolution
        assert ticks == pytest.approx(round(ticks), abs=1e-6)  # whole ticks only
        assert left == right
        # Counting whole ticks: never ahead of the truth, behind by less than one tick.
        assert 0.0 <= r.pose[0] - r.odometry.pose[0] < resolution + 1e-9
        reported.add(round(ticks))
    assert r.odometry.pose[0] - 2.0 == pytest.approx(math.floor(r.distance / resolution) * resolution)
    assert len(reported) > 100  # it counted, rather than standing still


def test_slipping_wheels_keep_counting_against_a_wall(make_sim):
    wall = {"type": "wall", "start": [4.0, 8.0], "end": [4.0, 12.0], "thickness": 0.1}
    sim = make_sim([robot([2, 10, 0.0], controller=wheels(0.5, 0.5))], obstacles=[wall])
    r = sim.robots["r"]
    sim.run(10.0)
    stop = 4.0 - 0.05 - r.radius
    assert r.pose[0] == pytest.approx(stop, abs=0.01)  # the robot stands at the wall
    left, right = r.odometry.wheel_travel
    # The wheels turned at the command the whole time: 0.5 m/s after a 1/6 s ramp at 3 m/s^2.
    commanded = 0.5 * 10.0 - 0.5 * 0.5 / 3.0 * 0.5
    assert left == pytest.approx(commanded, abs=0.01) and right == pytest.approx(left)
    assert r.odometry.pose[0] == pytest.approx(2.0 + left, abs=1e-9)
    result = sim.result()["robots"]["r"]
    assert result["odometry_error"] == pytest.approx(2.0 + left - r.pose[0], abs=1e-6)
    assert result["odometry_error"] > 3.0  # odometry ran ahead by the slipped travel


def test_odometry_noise_is_seeded(make_sim):
    def end_pose(seed):
        sim = make_sim([robot([5, 5, 0.0], odometry={"wheel_noise_std": 0.01},
                              controller=wheels(0.6, 0.5))], seed=seed)
        sim.run(3.0)
        return sim.robots["r"].odometry.pose, sim.robots["r"].pose

    (a, truth_a), (b, _), (c, truth_c) = end_pose(1), end_pose(1), end_pose(2)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)
    assert np.array_equal(truth_a, truth_c)  # the noise is in the estimate, not in the motion
    assert np.hypot(*(a - truth_a)[:2]) > 1e-4
