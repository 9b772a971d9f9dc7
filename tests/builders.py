"""Scenario mappings built in code for tests (import as ``from builders import robot``)."""
from __future__ import annotations

import math


def scenario(robots: list[dict], obstacles: list[dict] | None = None, size=(20.0, 20.0),
             **extra) -> dict:
    """A scenario mapping with sensible defaults; ``extra`` adds top-level keys or world keys."""
    world = {"size": list(size)}
    for key in ("dt", "substeps", "duration", "wall_friction"):
        if key in extra:
            world[key] = extra.pop(key)
    return {"name": "test", "world": world, "obstacles": obstacles or [], "robots": robots, **extra}


def drive_to_goal(sim, name: str, limit: float = 20.0) -> bool:
    """Step ``sim`` until robot ``name`` reaches its goal or ``limit`` [s] have passed; returns
    whether its controller ever waited for obstacles not on the map (its message says so)."""
    r = sim.robots[name]
    waited = False
    while sim.time < limit and not r.goal_reached:
        sim.step()
        waited = waited or "not on the map" in r.controller.message
    return waited


def robot(pose, **keys) -> dict:
    return {"name": keys.pop("name", "r"), "pose": list(pose), **keys}


def wheels(left: float, right: float) -> dict:
    return {"type": "wheels", "left": left, "right": right}


ROOM = (8.0, 5.0)  # [m] room_scan's walls at x = 0, 8 and y = 0, 5
ROOM_RANGE = 6.0  # [m] room_scan's LiDAR range


def room_scan(pose, time, walker=None, beams=360, fov=2 * math.pi, radius=0.25):
    """A LiDAR's LaserScan at ``pose`` [x, y, theta] in an empty 8 x 5 m room (ROOM), with a
    round walker of ``radius`` [m] at ``walker`` (x, y) if given; ranges capped at ROOM_RANGE."""
    import numpy as np

    from pymunk_bot.robots.readings import LaserScan
    from pymunk_bot.sensors import beam_angles

    angles = beam_angles(beams, fov)
    world = pose[2] + angles
    c, s = np.cos(world), np.sin(world)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (ROOM[0] - pose[0]) / c, np.where(c < 0, -pose[0] / c, np.inf))
        ty = np.where(s > 0, (ROOM[1] - pose[1]) / s, np.where(s < 0, -pose[1] / s, np.inf))
    ranges = np.minimum(tx, ty)
    if walker is not None:  # ray-circle intersection
        dx, dy = walker[0] - pose[0], walker[1] - pose[1]
        along = dx * c + dy * s
        miss2 = dx * dx + dy * dy - along * along
        hit = (along > 0) & (miss2 < radius ** 2)
        ranges = np.where(hit, np.minimum(ranges, along - np.sqrt(np.maximum(radius ** 2 - miss2,
                                                                               0))), ranges)
    return LaserScan(ranges=np.minimum(ranges, ROOM_RANGE), angles=angles, min_range=0.1,
                     max_range=ROOM_RANGE, offset=(0.0, 0.0, 0.0), time=time)
