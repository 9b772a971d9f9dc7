"""navigate: plans on the map, reaches goals in mazes, replans around the unmapped, fails clearly."""
import numpy as np
import pytest

from pathlib import Path

from pymunk_bot import Simulation

from builders import drive_to_goal
from helpers import LIDAR, maze_case, parallel, run_until_goal, scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
SEEDS = range(200, 208)


@pytest.mark.slow  # end-to-end, several seconds: .ci/run runs it (-m slow)
def test_reaches_the_goal_in_random_mazes_without_collisions():
    results = parallel(maze_case, SEEDS, [{"type": "navigate"}] * len(SEEDS))
    assert all(r["goal_reached"] for r in results), [r["controller_message"] for r in results]
    assert sum(r["collisions"] for r in results) == 0


def test_navigates_on_the_map_alone_without_a_lidar():
    results = parallel(maze_case, SEEDS[:4], [{"type": "navigate"}] * 4, [False] * 4)
    assert all(r["goal_reached"] and r["collisions"] == 0 for r in results)


def test_an_unreachable_goal_is_a_clear_failure_not_a_spin():
    sim = Simulation.from_file(SCENARIOS / "unreachable.yaml")
    sim.run(3.0)
    result = sim.result()["robots"]["r1"]
    assert result["controller_status"] == "failed"
    assert "no path" in result["controller_message"]
    assert result["path_length"] < 1e-6
    assert abs(sim.robots["r1"].velocity[1]) < 1e-9  # not turning either


def test_replans_around_a_crate_the_map_did_not_show():
    # A corridor with one gap in a wall; a movable crate (not on the map) blocks the gap,
    # the other way round the wall is longer but open.
    walls = [{"type": "wall", "start": [5.0, 0.0], "end": [5.0, 1.8], "thickness": 0.1},
             {"type": "wall", "start": [5.0, 3.0], "end": [5.0, 6.2], "thickness": 0.1},
             {"type": "box", "center": [5.0, 2.4], "size": [0.4, 1.3], "movable": True,
              "mass": 50.0}]
    # A short-range LiDAR: the crate is discovered on the way, after the first plan.
    robot = {"name": "r", "pose": [1.0, 2.4, 0.0], "lidar": {"beams": 180, "max_range": 2.0},
             "controller": {"type": "navigate"}, "goal": {"position": [9.0, 2.4]}}
    result = run_until_goal(scenario((10.0, 8.0), walls, [robot]), 45.0)["robots"]["r"]
    assert result["goal_reached"] and result["collisions"] == 0
    assert result["replans"] >= 2
    assert result["path_length"] > 10.0  # it went round the top, not through the crate


def test_gives_up_when_unmapped_obstacles_block_every_route():
    walls = [{"type": "wall", "start": [5.0, 0.0], "end": [5.0, 2.0], "thickness": 0.1},
             {"type": "wall", "start": [5.0, 2.8], "end": [5.0, 5.0], "thickness": 0.1},
             {"type": "box", "center": [5.0, 2.4], "size": [0.3, 0.7], "movable": True,
              "mass": 500.0}]
    robot = {"name": "r", "pose": [1.0, 2.4, 0.0], "lidar": LIDAR,
             "controller": {"type": "navigate", "give_up_after": 4.0},
             "goal": {"position": [9.0, 2.4]}}
    sim = Simulation(scenario((10.0, 5.0), walls, [robot]))
    sim.run(25.0)
    controller = sim.robots["r"].controller
    assert controller.status == "failed"
    assert "not on the map" in controller.message
    assert sim.robots["r"].collisions == 0
    distance = sim.robots["r"].distance
    sim.run(3.0)
    assert sim.robots["r"].distance == distance  # stopped for good


def test_drifting_odometry_is_what_it_navigates_on():
    # Odometry with a scale error: the controller sees the drifted pose; with ground truth
    # localisation the same robot ends closer to the goal.
    def run(localization):
        robot = {"name": "r", "pose": [1.0, 1.0, 0.0], "controller": {"type": "navigate"},
                 "localization": localization, "goal": {"position": [8.0, 5.0]},
                 "odometry": {"right_scale_error": 0.03}}
        sim = Simulation(scenario((10.0, 6.0), [], [robot]))
        sim.run(20.0)
        return float(np.hypot(*(sim.robots["r"].pose[:2] - (8.0, 5.0))))
    assert run("ground_truth") < 0.1
    assert run("odometry") > 0.15


@pytest.mark.parametrize("rate", [5.0, 7.0])  # [Hz] slower than the 10 Hz controller; in step or not
def test_turning_on_the_spot_does_not_wall_itself_in_with_its_own_scans(rate):
    # A room with a door onto a corridor; the goal is down the corridor, so the robot first
    # turns on the spot towards the door. The controller is handed the LiDAR's latest scan on
    # every tick; placed with the pose of a later tick, a turn copies the room's walls around
    # the robot as "unmapped obstacles" (office seed 11's tour gave up, docs/localization-journal.md).
    walls = [{"type": "wall", "start": [0.0, 3.3], "end": [4.6, 3.3], "thickness": 0.1},
             {"type": "wall", "start": [5.5, 3.3], "end": [8.0, 3.3], "thickness": 0.1},
             {"type": "wall", "start": [3.4, 0.0], "end": [3.4, 3.3], "thickness": 0.1},
             {"type": "wall", "start": [0.0, 4.9], "end": [8.0, 4.9], "thickness": 0.1}]
    for heading in np.radians(np.arange(0.0, 360.0, 45.0)):  # [rad] facing every way at first
        robot = {"name": "r", "pose": [5.5, 1.8, float(heading)],
                 "lidar": {"beams": 270, "max_range": 8.0, "rate": rate},
                 "controller": {"type": "navigate"},
                 "goal": {"position": [1.0, 4.1], "tolerance": 0.25}}
        sim = Simulation(scenario((8.0, 5.0), walls, [robot]))
        r = sim.robots["r"]
        blocked = drive_to_goal(sim, "r")
        assert r.goal_reached and r.collisions == 0, (heading, r.controller.message)
        assert not blocked, heading  # nothing but the map is there: nothing to wait for
