"""The LiDAR in the real simulation against pymunk's own segment queries, in random worlds.

Noise off, the sensor must read what one ``segment_query_first`` per beam reads, to 1e-6 m,
whatever the world holds (rotated boxes, circles, concave polygons, walls, crates being
pushed, other robots) and wherever the robots have driven.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import TypeAdapter
from builders import robot, scenario

from pymunk_bot import Simulation
from pymunk_bot.config import parse_scenario
from pymunk_bot.config.assemble import obstacle_union
from pymunk_bot.config.outlines import distance_to_obstacle
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.sensors.raycast import reference_cast

SIZE = 20.0  # [m]
OBSTACLE = TypeAdapter(obstacle_union())


def random_obstacle(rng: np.random.Generator) -> dict:
    kind = rng.choice(["box", "circle", "polygon", "wall"])
    centre = rng.uniform(1.0, SIZE - 1.0, 2)
    movable = bool(rng.random() < 0.3)
    if kind == "box":
        return {"type": "box", "center": centre.tolist(), "size": rng.uniform(0.2, 1.5, 2).tolist(),
                "angle": float(rng.uniform(-math.pi, math.pi)), "movable": movable}
    if kind == "circle":
        return {"type": "circle", "center": centre.tolist(), "radius": float(rng.uniform(0.1, 0.8)),
                "movable": movable}
    if kind == "polygon":  # a star-shaped outline: concave, never self-crossing
        n = int(rng.integers(4, 9))
        angles = np.sort(rng.uniform(0, 2 * math.pi, n))
        radii = rng.uniform(0.3, 1.0, n)
        points = centre + np.column_stack((radii * np.cos(angles), radii * np.sin(angles)))
        return {"type": "polygon", "points": points.tolist()}
    end = centre + rng.uniform(-2.0, 2.0, 2)
    return {"type": "wall", "start": centre.tolist(), "end": np.clip(end, 0.5, SIZE - 0.5).tolist(),
            "thickness": float(rng.uniform(0.02, 0.2))}


def random_lidar(rng: np.random.Generator) -> dict:
    return {"beams": int(rng.integers(50, 400)),
            "fov": float(rng.choice([2 * math.pi, rng.uniform(0.5, 6.0)])),
            "max_range": float(rng.uniform(2.0, 25.0)),
            "min_range": float(rng.choice([0.0, 0.1])),
            "rate": float(rng.choice([10.0, 60.0])),
            "offset": [float(rng.uniform(-0.1, 0.1)), float(rng.uniform(-0.1, 0.1)),
                       float(rng.uniform(-math.pi, math.pi))]}


def bounding_circle(obstacle: dict) -> tuple[tuple[float, float], float]:
    """A circle around an obstacle: only robots inside it need the exact distance check."""
    if obstacle["type"] == "circle":
        return tuple(obstacle["center"]), obstacle["radius"]
    if obstacle["type"] == "box":
        return tuple(obstacle["center"]), math.hypot(*obstacle["size"]) / 2
    points = np.array(obstacle["points"] if obstacle["type"] == "polygon"
                      else [obstacle["start"], obstacle["end"]])
    centre = points.mean(axis=0)
    return tuple(centre), float(np.max(np.hypot(*(points - centre).T))) + 0.1


def random_world(seed: int, obstacle_count: tuple[int, int], robot_count: int) -> Simulation:
    rng = np.random.default_rng(seed)
    for _ in range(100):  # redraw until the scenario is valid (e.g. polygons too thin)
        obstacles = [random_obstacle(rng) for _ in range(int(rng.integers(*obstacle_count)))]
        parsed = [OBSTACLE.validate_python(o) for o in obstacles]
        bounds = [bounding_circle(o) for o in obstacles]
        robots = []
        for _ in range(50 * robot_count):
            if len(robots) == robot_count:
                break
            x, y = rng.uniform(0.5, SIZE - 0.5, 2)
            radius = float(rng.uniform(0.15, 0.3))
            clear = all(math.dist((x, y), c) > radius + 0.05 + reach
                        or distance_to_obstacle((x, y), o) > radius + 0.05
                        for o, (c, reach) in zip(parsed, bounds))
            clear &= all(math.dist((x, y), b["pose"][:2]) > radius + b["radius"] + 0.05 for b in robots)
            if clear:
                left, right = rng.uniform(-1.0, 1.0, 2)
                robots.append(robot([x, y, rng.uniform(-math.pi, math.pi)], name=f"r{len(robots)}",
                                    radius=radius, lidar=random_lidar(rng),
                                    controller={"type": "wheels", "left": left, "right": right}))
        try:
            return Simulation(parse_scenario(scenario(robots, obstacles, size=(SIZE, SIZE)), "random"))
        except ScenarioError:
            continue
    raise RuntimeError("no valid random world")


def reference_ranges(sim: Simulation, r) -> np.ndarray:
    """What pymunk's segment queries see, with the sensor's min_range rule."""
    c = r.lidar.config
    ranges = reference_cast(sim.space, r.lidar.origin(), r.pose[2] + r.lidar.angles,
                            c.max_range, r.shape.filter)
    ranges[ranges < c.min_range] = c.max_range
    return ranges


@pytest.mark.parametrize("seed,obstacle_count,robot_count", [
    *[(seed, (5, 40), 5) for seed in range(10)],
    (100, (300, 400), 12),  # dense: hundreds of obstacles, a dozen robots
    pytest.param(101, (300, 400), 12, marks=pytest.mark.slow),  # a second dense world
])
def test_lidar_matches_segment_queries_in_random_worlds(seed, obstacle_count, robot_count):
    sim = random_world(seed, obstacle_count, robot_count)
    checked = 0
    for _ in range(4):
        sim.run(0.5)
        for r in sim.robots.values():
            expected = reference_ranges(sim, r)
            assert np.max(np.abs(r.lidar.scan() - expected)) <= 1e-6
            if r.lidar.latest.time == pytest.approx(sim.time):  # a scan was due on this tick
                assert np.max(np.abs(r.lidar.ranges - expected)) <= 1e-6
                checked += 1
    assert checked > 0
    # The worlds are not empty: beams hit things short of their range.
    hits = [np.mean(r.lidar.ranges < r.lidar.config.max_range) for r in sim.robots.values()]
    assert max(hits) > 0.5
