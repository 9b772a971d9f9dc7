"""Metrics of scripted runs whose values are known: a straight drive past a person standing
still, into a person, into a wall."""
import math

import pytest

import pymunk_bot as pb
from pymunk_bot.config.metric_bounds import BOUND_KEYS, MetricBounds
from pymunk_bot.outcomes.navigation import METRIC_NAMES, Thresholds, track


def scene(person_y=3.0, goal_x=7.0, expect=None, v=0.5):
    """A robot (r = 0.2) driving along y = 2 at v; a person (r = 0.25) standing at (4, y)."""
    data = {
        "name": "scripted", "world": {"size": [10.0, 5.0], "duration": 14.0},
        "obstacles": [{"type": "pedestrian", "center": [4.0, person_y], "goals": [[4.0, person_y]],
                       "mode": "once", "react_to_robot": False}],
        "robots": [{"name": "r1", "pose": [1.0, 2.0, 0.0], "radius": 0.2, "max_accel": 3.0,
                    "controller": {"type": "velocity", "v": v, "omega": 0.0},
                    "goal": {"position": [goal_x, 2.0], "tolerance": 0.2}}]}
    if expect is not None:
        data["expect"] = {"r1": expect}
    return data


def test_driving_past_a_person_standing_still():
    sim = pb.Simulation.from_dict(scene())
    wide = track(sim, "r1", Thresholds(personal_space=0.6))
    sim.run(13.0)
    m = sim.result()["robots"]["r1"]["metrics"]  # a crowd scenario reports them itself
    assert list(m) == list(METRIC_NAMES)
    assert m["success"] == 1.0 and m["timeout"] == 0.0 and m["collision"] == 0.0
    # closest at x = 4: 1 m between centres, less 0.2 + 0.25
    assert m["min_distance_to_human"] == pytest.approx(0.55, abs=2e-3)
    assert m["personal_space_intrusions"] == 0.0 and m["personal_space_time"] == 0.0
    w = wide.values()
    assert w["personal_space_intrusions"] == 1.0
    # within 0.6 m while |x - 4| < sqrt(1.05^2 - 1) at 0.5 m/s
    assert w["personal_space_time"] == pytest.approx(2 * math.sqrt(1.05 ** 2 - 1) / 0.5, abs=0.05)
    # the goal is 6 m ahead, reached 0.2 m short of it; L* = 6 m, so SPL is 1
    assert m["path_length"] == pytest.approx(5.8, abs=0.02)
    assert m["spl"] == 1.0
    assert m["time_to_goal"] == pytest.approx(5.8 / 0.5, abs=0.2)
    assert m["max_speed"] == pytest.approx(0.5, abs=1e-6)
    assert m["mean_speed"] == pytest.approx(0.5, abs=0.02)
    # passing 1 m to the side at constant velocity: never on a collision course
    assert math.isinf(m["min_time_to_collision"])
    assert m["human_impulse"] == 0.0
    assert m["clearing_distance"] == pytest.approx(0.8, abs=1e-3)  # the arena wall behind, x = 0


def test_driving_into_a_person_is_a_human_collision_with_impulse():
    sim = pb.Simulation.from_dict(scene(person_y=2.0))
    sim.run(8.0)
    m = sim.result()["robots"]["r1"]["metrics"]
    assert m["collision_human"] == 1.0 and m["collision_wall"] == 0.0
    assert m["min_distance_to_human"] <= 0.01
    assert m["min_time_to_collision"] == 0.0
    assert m["human_impulse"] > 0.0 and m["peak_human_force"] > 0.0
    assert m["success"] == 0.0


def test_a_wall_contact_is_a_wall_collision():
    data = scene(person_y=4.5, goal_x=9.5, v=1.0)
    data["obstacles"].append({"type": "box", "center": [6.0, 2.0], "size": [0.4, 2.0]})
    sim = pb.Simulation.from_dict(data)
    sim.run(8.0)
    m = sim.result()["robots"]["r1"]["metrics"]
    assert m["collision_wall"] == 1.0 and m["collision_human"] == 0.0
    assert m["human_impulse"] == 0.0
    assert m["stalled_time"] > 1.0  # pressed against the box, not moving


def test_runs_without_crowd_or_bounds_measure_nothing():
    data = scene()
    data["obstacles"] = []
    sim = pb.Simulation.from_dict(data)
    assert not sim.built.metrics  # no per-tick cost
    assert "metrics" not in sim.result()["robots"]["r1"]


def test_expect_bounds_on_metrics():
    ok = pb.Simulation.from_dict(scene(expect={"min_distance_to_human": 0.5, "spl": 0.9,
                                               "max_human_impulse": 0.0}))
    ok.run(14.0)  # SPL depends on how the run ends: decided at its duration
    assert ok.verdict().status == "passed"
    bad = pb.Simulation.from_dict(scene(expect={"min_distance_to_human": 0.6}))
    bad.run(13.0)
    verdict = bad.verdict()
    assert verdict.status == "failed"
    (check,) = verdict.checks
    assert check.key == "min_distance_to_human" and check.by == pytest.approx(0.05, abs=3e-3)


def test_every_metric_has_a_bound_key():
    assert set(BOUND_KEYS) == set(MetricBounds.model_fields)
    assert {"min_distance_to_human", "max_human_impulse", "spl",
            "max_personal_space_time"} <= set(BOUND_KEYS)


def test_unknown_metric_in_expect_is_one_line_exit_2(tmp_path, capsys):
    import yaml
    from pymunk_bot.cli import main

    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(scene(expect={"max_human_impulses": 0.0})))
    assert main(["run", str(path), "--headless"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "bad.yaml" in err[0] and "expect.r1.max_human_impulses" in err[0]
    assert "max_human_impulse" in err[0]  # did you mean


def test_a_tracker_follows_the_run_through_resets():
    data = scene()
    data["obstacles"] = []  # nothing measured by the run itself: the tracker's own recorder
    sim = pb.Simulation.from_dict(data)
    metrics = track(sim, "r1", Thresholds(stall_speed=0.01))
    sim.run(2.0)
    assert metrics.values()["path_length"] == pytest.approx(0.5 * 2.0, abs=0.05)
    assert math.isinf(metrics.values()["min_distance_to_human"])  # no pedestrians
    sim.reset()
    assert metrics.values()["path_length"] == 0.0  # a new episode, measured from its start
    sim.run(1.0)
    assert metrics.values()["path_length"] == pytest.approx(0.5, abs=0.05)


def test_an_arrival_after_a_collision_is_reached_not_success():
    """The robot grazes a person standing 0.4 m off its line, then drives on to the goal."""
    sim = pb.Simulation.from_dict(scene(person_y=2.4))
    sim.run(13.0)
    m = sim.result()["robots"]["r1"]["metrics"]
    assert m["collision"] == 1.0 and m["collision_human"] == 1.0
    assert m["reached"] == 1.0 and m["success"] == 0.0


def test_discomfort_is_the_share_of_time_within_0_2_m():
    """A person 0.6 m off the line: clearance 0.6 - 0.45 = 0.15 m at the closest, below 0.2 m
    while |x - 4| < sqrt(0.65^2 - 0.6^2) = 0.25 m, 1 s at 0.5 m/s, of the 11.6 s to the goal."""
    sim = pb.Simulation.from_dict(scene(person_y=2.6))
    sim.run(13.0)
    m = sim.result()["robots"]["r1"]["metrics"]
    assert m["success"] == 1.0 and m["reached"] == 1.0 and m["collision"] == 0.0
    assert m["discomfort"] == pytest.approx(1.0 / m["time_to_goal"], abs=0.005)
