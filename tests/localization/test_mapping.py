"""Occupancy-grid mapping from LiDAR with known poses."""
import dataclasses

import numpy as np
import pytest

from pymunk_bot import Simulation
from pymunk_bot.localization import MappingConfig, OccupancyMapper, check_mapping
from pymunk_bot.localization.metrics import map_scores
from pymunk_bot.maps.rasterize import scenario_grid

ROOM = {"name": "room", "world": {"size": [4.0, 3.0]},
        "obstacles": [{"type": "box", "center": [2.8, 1.5], "size": [0.4, 0.4]}],
        "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.3],
                    "lidar": {"beams": 360, "max_range": 6.0, "noise_std": 0.01}}]}


def _mapped(poses):
    """A mapper fed one scan from each (x, y), taken where the robot is put."""
    sim = Simulation.from_dict(ROOM)
    robot = sim.robots["r1"]
    mapper = OccupancyMapper.for_arena(MappingConfig(), (4.0, 3.0))
    for x, y in poses:
        robot.body.position = (x, y)
        scan = dataclasses.replace(robot.lidar.latest, ranges=robot.lidar.scan())
        mapper.integrate(robot.pose, scan)
    return sim, mapper


def test_walls_are_occupied_the_room_free_and_the_outside_unknown():
    sim, mapper = _mapped([(1.0, 1.0), (1.0, 2.2), (3.5, 0.5)])
    grid = mapper.grid
    truth = scenario_grid(sim.config, 0.05)
    scores = map_scores(grid, truth)
    assert scores["precision"] >= 0.95
    assert scores["recall"] >= 0.9
    # the robot's own spot is free, a point beyond the walls is unknown
    r, c = grid.cell_of(np.array([1.5, 1.5]))
    assert 0 <= grid.data[r, c] < 50  # more likely free than not after a few looks
    r, c = grid.cell_of(np.array([-0.5, -0.5]))
    assert grid.data[r, c] == -1
    r, c = grid.cell_of(np.array([2.61, 1.5]))  # the box's left face
    assert grid.data[r, c] >= 65


def test_repeated_misses_clear_a_cell_that_was_hit_once():
    config = MappingConfig()
    mapper = OccupancyMapper(config, ((0.0, 0.0), (2.0, 2.0)))

    class Scan:  # one beam ending at 1.5 m, then the same beam reading 1.9 m (the thing moved)
        angles = np.array([0.0])
        min_range, max_range, offset, time = 0.05, 3.0, (0.0, 0.0, 0.0), 0.0

        def __init__(self, r):
            self.ranges = np.array([r])

    pose = np.array([0.1, 1.0, 0.0])
    mapper.integrate(pose, Scan(1.5))
    cell = mapper.grid.cell_of(np.array([1.6, 1.0]))
    assert mapper.grid.data[cell] >= 65
    for _ in range(8):
        mapper.integrate(pose, Scan(1.9))
    assert mapper.grid.data[cell] < 20


def test_a_map_too_large_is_refused_with_the_limit_named():
    with pytest.raises(ValueError, match="over the limit of 16000000"):
        check_mapping(MappingConfig(resolution=0.01), (1000.0, 1000.0))
    with pytest.raises(ValueError, match="exceeds the limit"):
        OccupancyMapper(MappingConfig(resolution=0.01), ((0, 0), (1000.0, 1000.0)))
