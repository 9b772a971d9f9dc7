"""Clearance grid, A* and smoothing on maps a user would draw."""
import math

import numpy as np
import pytest

from pymunk_bot.geometry import plane as geo
from pymunk_bot.config.loader import parse_scenario
from pymunk_bot.planning import ClearanceGrid, MapInfo, astar, path_length, shortcut
from pymunk_bot.planning.layouts import maze_walls


def scenario_map(size, obstacles):
    config = parse_scenario({"name": "m", "world": {"size": list(size)}, "obstacles": obstacles,
                             "robots": [{"name": "r", "pose": [0.3, 0.3, 0.0]}]}, "test")
    return MapInfo.from_scenario(config)


def path_clearance(grid, path):
    return min(grid.segment_clearance(a, b) for a, b in zip(path, path[1:]))


def test_clearance_is_the_distance_to_the_nearest_surface():
    box = {"type": "box", "center": [3.0, 2.0], "size": [1.0, 0.6], "angle": 0.5}
    circle = {"type": "circle", "center": [6.0, 3.0], "radius": 0.5}
    grid = ClearanceGrid.from_map(scenario_map((8.0, 5.0), [box, circle]), 0.05, 2.0)
    corners = geo.box_corners((3.0, 2.0), (1.0, 0.6), 0.5)
    rng = np.random.default_rng(0)
    for x, y in rng.uniform((0.5, 0.5), (7.5, 4.5), size=(200, 2)):
        row, col = grid.cell_of(x, y)
        cx, cy = grid.center_of(row, col)
        exact = min(geo.distance_to_polygon((cx, cy), corners),
                    max(0.0, math.dist((cx, cy), (6.0, 3.0)) - 0.5),
                    cx, 8.0 - cx, cy, 5.0 - cy, 2.0)
        assert grid.clearance[row, col] == pytest.approx(exact, abs=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_astar_crosses_random_mazes_keeping_the_robot_clear(seed):
    walls = maze_walls(np.random.default_rng(seed), 8, 8, 1.0, 0.1)
    grid = ClearanceGrid.from_map(scenario_map((8.0, 8.0), walls), 0.1, 0.6)
    result = astar(grid, (0.5, 0.5), (7.5, 7.5), hard=0.22, soft=0.45)
    assert result.found, result.reason
    assert result.path[0] == (0.5, 0.5) and result.path[-1] == (7.5, 7.5)
    assert path_clearance(grid, result.path) >= 0.22 - 0.05
    smooth = shortcut(grid, result.path, 0.45)
    assert path_length(smooth) <= path_length(result.path) + 1e-9
    assert len(smooth) < len(result.path) / 3
    # Smoothing never brings the path closer to the walls than the grid path went (less
    # the sampling slack), nor through them.
    assert path_clearance(grid, smooth) >= path_clearance(grid, result.path) - 0.03


def test_a_closed_room_has_no_path_and_says_why():
    room = [{"type": "wall", "start": s, "end": e, "thickness": 0.1} for s, e in
            [([5, 1], [7, 1]), ([7, 1], [7, 4]), ([7, 4], [5, 4]), ([5, 4], [5, 1])]]
    grid = ClearanceGrid.from_map(scenario_map((8.0, 5.0), room), 0.1, 0.6)
    result = astar(grid, (1.0, 2.5), (6.0, 2.5), hard=0.22, soft=0.45)
    assert not result.found
    assert "no path" in result.reason and "(6.00, 2.50)" in result.reason
    inside = astar(grid, (1.0, 2.5), (5.0, 2.5), hard=0.22, soft=0.45)
    assert "inside an obstacle" in inside.reason


@pytest.mark.parametrize("door, passable", [(0.55, True), (0.50, True), (0.40, False)])
def test_a_doorway_is_open_exactly_when_the_robot_fits(door, passable):
    half = door / 2
    walls = [{"type": "wall", "start": [4.0, 0.0], "end": [4.0, 2.5 - half], "thickness": 0.1},
             {"type": "wall", "start": [4.0, 2.5 + half], "end": [4.0, 5.0], "thickness": 0.1}]
    grid = ClearanceGrid.from_map(scenario_map((8.0, 5.0), walls), 0.05, 0.6)
    result = astar(grid, (1.0, 1.0), (7.0, 1.0), hard=0.21, soft=0.45)
    assert result.found == passable
    if passable:  # through the doorway, not around (there is no around)
        assert path_clearance(grid, result.path) >= 0.21 - 0.04


def test_paths_prefer_room_when_there_is_room():
    # A pillar in a 3 m wide room: the path passes it with the soft margin, not grazing it.
    pillar = {"type": "circle", "center": [4.0, 1.5], "radius": 0.5}
    grid = ClearanceGrid.from_map(scenario_map((8.0, 3.0), [pillar]), 0.05, 0.8)
    result = astar(grid, (1.0, 1.5), (7.0, 1.5), hard=0.22, soft=0.5)
    smooth = shortcut(grid, result.path, 0.5)
    assert path_clearance(grid, smooth) >= 0.45
