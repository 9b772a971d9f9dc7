"""How many pymunk substeps per dt a scenario needs so that nothing tunnels (pure geometry)."""
from __future__ import annotations

import math

import numpy as np

from .. import geometry as geo
from .schema import CircleObstacle, ScenarioConfig

ARENA_WALL_THICKNESS = 1.0  # [m]; thick so that nothing can tunnel out of the arena


def substeps_against_tunnelling(dt: float, max_speed: float, robot_radius: float,
                                thinnest_half_width: float, safety: float = 2.0) -> int:
    """Smallest substep count so that nothing moves more than a fraction of a collision depth.

    A disc of radius r passes through a wall of half-width w once its centre crosses the wall's
    middle within one substep, i.e. when ``v * dt / k > r + w``. We keep a factor ``safety`` below.
    """
    depth = robot_radius + thinnest_half_width
    return max(1, math.ceil(max_speed * dt * safety / depth))


def half_width(obstacle) -> float:
    """Half the thinnest extent of an obstacle: what a fast robot must not skip over."""
    if isinstance(obstacle, CircleObstacle) or getattr(obstacle, "type", "") == "pedestrian":
        return obstacle.radius
    from .semantics import obstacle_outline
    return geo.thinness(obstacle_outline(obstacle)) / 2.0


def mover_speed(obstacle) -> float:
    """Fastest a scripted obstacle or a pedestrian moves [m/s] (0 for the others)."""
    if getattr(obstacle, "type", "") == "pedestrian":
        from ..actors.pedestrians import MAX_SPEED_FACTOR
        return MAX_SPEED_FACTOR * (obstacle.speed + 3.0 * obstacle.speed_std)
    motion = getattr(obstacle, "motion", None)
    if motion is None:
        return 0.0
    reach = 0.0
    if motion.angular_speed:
        from .semantics import obstacle_outline
        outline = obstacle_outline(obstacle)
        if outline is not None:
            reach = float(np.hypot(*(outline - outline.mean(axis=0)).T).max())
    return motion.speed + abs(motion.angular_speed) * reach


def required_substeps(scenario: ScenarioConfig) -> int:
    """Substeps for the fastest robot against the thinnest obstacle (and robots head-on, and
    moving obstacles or pedestrians closing on a robot)."""
    from ..footprint import of_robot
    dt = scenario.world.dt
    robots = scenario.robots
    fastest = max(r.top_speed() for r in robots)
    smallest = min(of_robot(r).half_thickness for r in robots)
    thinnest = min([ARENA_WALL_THICKNESS / 2] + [half_width(o) for o in scenario.obstacles])
    substeps = substeps_against_tunnelling(dt, fastest, smallest, thinnest)
    if len(robots) > 1:  # two robots closing head-on
        substeps = max(substeps, substeps_against_tunnelling(dt, 2 * fastest, smallest, smallest))
    for obstacle in scenario.obstacles:
        speed = mover_speed(obstacle)
        if speed > 0:
            substeps = max(substeps, substeps_against_tunnelling(
                dt, fastest + speed, smallest, half_width(obstacle)))
    return substeps
