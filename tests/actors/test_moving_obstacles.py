"""Scripted obstacles: they follow their paths exactly, push crates, and LiDAR sees them move."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot

from pymunk_bot.actors import PathScript
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.planning.map import MapInfo

PATH = [[2.0, 2.0], [6.0, 2.0], [6.0, 4.0]]  # 6 m long


def mover(mode: str, speed: float = 1.0, **extra) -> dict:
    return {"type": "box", "center": [2.0, 2.0], "size": [0.4, 0.4],
            "motion": {"path": PATH, "speed": speed, "mode": mode}, **extra}


@pytest.mark.parametrize("mode, seconds, expected", [
    ("once", 5.0, (6.0, 3.0)), ("once", 9.0, (6.0, 4.0)),       # stops at the end
    ("pingpong", 8.0, (6.0, 2.0)), ("pingpong", 11.0, (3.0, 2.0)),  # comes back
    ("loop", 7.0, (6.0, 4.0 - 1.0 / math.sqrt(5.0) * 1.0 * 1.0)),    # closing leg back to start
])
def test_follows_its_path(make_sim, mode, seconds, expected):
    sim = make_sim([robot([1, 7, 0])], [mover(mode)], size=(8.0, 8.0))
    sim.run(seconds)
    if mode == "loop":  # 1 m along the closing leg from (6, 4) toward (2, 2)
        direction = np.array([-4.0, -2.0]) / math.hypot(4.0, 2.0)
        expected = tuple(np.array([6.0, 4.0]) + direction)
    x, y = sim.world.obstacles[0].body.position
    assert (x, y) == pytest.approx(expected, abs=1e-9)


def test_script_positions_every_tick(make_sim):
    sim = make_sim([robot([1, 7, 0])], [mover("pingpong", speed=0.7)], size=(8.0, 8.0))
    script = PathScript(PATH, 0.7, "pingpong")
    for _ in range(600):
        sim.step()
        assert tuple(sim.world.obstacles[0].body.position) == pytest.approx(
            tuple(script.position(sim.time)), abs=1e-9)


def test_pushes_a_crate_out_of_its_way(make_sim):
    crate = {"type": "box", "center": [4.0, 2.0], "size": [0.4, 0.4], "movable": True, "mass": 2.0}
    sim = make_sim([robot([1, 7, 0])], [mover("once"), crate], size=(8.0, 8.0))
    sim.run(3.5)  # the mover's centre is at x = 5.5: the crate is ahead of it
    x, y = sim.world.obstacles[1].body.position
    assert x >= 5.5 + 0.4 - 0.01
    assert y == pytest.approx(2.0, abs=0.05)


def test_pushes_a_robot_that_stands_in_the_way_and_it_counts_as_a_collision(make_sim):
    sim = make_sim([robot([4, 2, 0])], [mover("once", speed=0.5)], size=(8.0, 8.0))
    sim.run(8.0)
    r = sim.robots["r"]
    assert r.pose[0] > 5.0 and r.collisions >= 1


def test_lidar_sees_it_where_it_is(make_sim):
    lidar = {"beams": 4, "fov": 2 * math.pi, "max_range": 10.0}
    sim = make_sim([robot([4.0, 6.0, -math.pi / 2], lidar=lidar)],
                   [mover("once", speed=1.0)], size=(8.0, 8.0))
    sim.run(2.0)  # centre at (4, 2): top face at y = 2.2, 3.8 m below the robot
    lidar = sim.robots["r"].lidar
    ahead = int(np.argmin(np.abs(lidar.angles)))
    assert lidar.scan()[ahead] == pytest.approx(3.8, abs=1e-6)
    sim.run(1.0)  # moved on to (5, 2): the beam now reaches the floor wall at y = 0
    assert lidar.scan()[ahead] == pytest.approx(6.0, abs=1e-6)


def test_is_not_on_the_planning_map(make_sim):
    sim = make_sim([robot([1, 7, 0])], [mover("loop"), {"type": "box", "center": [1, 1],
                                                         "size": [0.2, 0.2]}], size=(8.0, 8.0))
    info = MapInfo.from_scenario(sim.config)
    assert len(info.polygons) == 1
    assert np.allclose(info.polygons[0].points.mean(axis=0), (1.0, 1.0))


@pytest.mark.parametrize("obstacle, message", [
    (mover("loop") | {"motion": {"path": [[2, 2], [9, 2]], "speed": 1.0}},
     r"obstacles\[0\]\.motion\.path\[1\]: \(9, 2\) takes the obstacle out of the arena"),
    (mover("loop") | {"motion": {"path": [[2, 2], [7.9, 2]], "speed": 1.0}},
     r"motion\.path\[1\]: .* out of the arena"),  # the box's edge would leave it
    (mover("loop") | {"motion": {"path": [[3, 2], [5, 2]], "speed": 1.0}},
     r"motion\.path\[0\]: the path must start at the obstacle's center"),
    (mover("loop", movable=True), r"motion: a scripted obstacle cannot also be movable"),
    (mover("loop") | {"motion": {"path": [[2, 2], [4, 2]], "speed": -1.0}},
     r"motion\.speed: "),
])
def test_bad_motion_is_a_one_line_error(make_sim, obstacle, message):
    with pytest.raises(ScenarioError, match=message):
        make_sim([robot([1, 7, 0])], [obstacle], size=(8.0, 8.0))


def test_substeps_account_for_a_fast_mover(make_sim):
    slow = make_sim([robot([1, 7, 0])], [mover("loop", speed=0.5)], size=(8.0, 8.0))
    fast = make_sim([robot([1, 7, 0])], [mover("loop", speed=15.0)], size=(8.0, 8.0))
    assert fast.substeps > slow.substeps
