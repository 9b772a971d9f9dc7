"""Building and running small scenarios for controller tests (in parallel over the cores)."""
from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from pymunk_bot import Simulation
from pymunk_bot.config.loader import parse_scenario
from pymunk_bot.planning.layouts import clutter, maze_walls

LIDAR = {"beams": 180, "max_range": 5.0}


def scenario(size, obstacles, robots, **extra):
    data = {"name": "t", "world": {"size": list(size)}, "obstacles": obstacles, "robots": robots}
    data.update(extra)
    return parse_scenario(data, "test")


def run_until_goal(config, limit: float) -> dict:
    """Run until every robot with a goal reached it, or ``limit`` seconds; the JSON result."""
    sim = Simulation(config)
    robots = [r for r in sim.robots.values() if r.goal is not None]
    while sim.time < limit and not all(r.goal_reached for r in robots):
        sim.step()
    result = sim.result()
    for name, r in sim.robots.items():
        result["robots"][name]["replans"] = getattr(r.controller, "replans", 0)
    return result


def maze_case(seed: int, controller: dict, lidar: bool = True) -> dict:
    walls = maze_walls(np.random.default_rng(seed), 6, 6, 1.2, 0.1, extra_openings=0.1)
    robot = {"name": "r", "pose": [0.6, 0.6, 0.0], "controller": controller,
             "goal": {"position": [6.6, 6.6]}}
    if lidar:
        robot["lidar"] = LIDAR
    return run_until_goal(scenario((7.2, 7.2), walls, [robot]), 60.0)["robots"]["r"]


def clutter_case(seed: int, controller: dict) -> dict:
    obstacles = clutter(np.random.default_rng(seed), (12.0, 8.0), 25,
                        [(1, 4, 0.8), (11, 4, 0.8)], 0.6)
    robot = {"name": "r", "pose": [1.0, 4.0, 0.0], "lidar": LIDAR, "controller": controller,
             "goal": {"position": [11.0, 4.0]}}
    return run_until_goal(scenario((12.0, 8.0), obstacles, [robot]), 40.0)["robots"]["r"]


def parallel(fn, *argument_lists):
    """fn over zipped argument lists, on every core."""
    with ProcessPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        return list(pool.map(fn, *argument_lists))
