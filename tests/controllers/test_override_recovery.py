"""After a manual override, a controller arrives or ends with a failure status and a message
(issue 35): it never stands still with status "running" for the rest of the run."""
from __future__ import annotations

import pytest

from override_trials import Trial, describe, draw_trials, run_trial


@pytest.mark.parametrize("start", [3.5, 4.0, 5.0, 5.5, 6.0, 8.5])
def test_warehouse_robot_left_against_a_shelf_backs_off_and_arrives(start):
    # The tracker's case: 2 s of (0.3 m/s, 0.5 rad/s) leaves the robot pressed against a shelf,
    # where every arc the path asks for came closer than the window allowed: it stood still.
    outcome = run_trial(Trial("warehouse", "r1", start, 2.0, 0.3, 0.5))
    assert outcome.status == "arrived", describe(outcome)


def test_waypoints_pressed_against_a_wall_fail_with_a_message_instead_of_pushing_for_ever():
    # Waypoints see nothing: its route runs into a wall across the arena (ground truth pose:
    # odometry would count the wheels slipping as progress). It used to push
    # against it with status "running" until the run ended.
    import pymunk_bot as pb

    sim = pb.Simulation.from_dict({
        "name": "wall_across", "world": {"size": [6.0, 3.0]},
        "obstacles": [{"type": "box", "center": [3.0, 1.5], "size": [0.4, 3.0]}],
        "robots": [{"name": "r1", "pose": [1.0, 1.5, 0.0], "localization": "ground_truth",
                    "controller": {"type": "waypoints", "points": [[5.0, 1.5]],
                                   "give_up_after": 4.0}}]})
    robot = sim.robots["r1"]
    sim.run(12.0)  # about 2 s to the wall, then 4 s without progress
    assert robot.controller.status == "failed"
    assert robot.controller.message.startswith("no progress toward the goal for 4 s")
    assert robot.pose[0] < 2.9  # it stopped at the wall


def test_sampled_overrides_end_in_arrival_or_a_stated_failure():
    # A quick sample for every run of the suite; the slow test below draws the 200.
    bad = [describe(o) for o in map(run_trial, draw_trials(8, seed=35)) if not o.ok]
    assert not bad, "\n".join(bad)


@pytest.mark.slow
def test_two_hundred_sampled_overrides_end_in_arrival_or_a_stated_failure():
    bad = [describe(o) for o in map(run_trial, draw_trials(200, seed=2026)) if not o.ok]
    assert not bad, "\n".join(bad)
