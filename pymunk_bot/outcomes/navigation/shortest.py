"""L*, the shortest collision-free path of the static world, for SPL.

A* (uniform cost: no clearance penalty) on a grid of the scenario's static map, inflated by
the robot's bounding radius, then string-pulled; pedestrians, scripted and movable obstacles
are not on it (they are not part of the static world). Plans are cached per process, so a
benchmark plans each (world, start, goal, radius) once.
"""
from __future__ import annotations

import hashlib
import math
from typing import Any

from pymunk_bot.config.checks import MAX_GRID_CELLS
from pymunk_bot.planning.astar import astar
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.planning.paths import path_length, shortcut

MAX_CACHED = 256  # plans kept per process
_cache: dict[tuple, float] = {}


def world_key(config: Any) -> str:
    """A hash of what the static map is made of: the world section and the obstacles."""
    text = config.world.model_dump_json() + "".join(
        o.model_dump_json() for o in config.obstacles if getattr(o, "type", "") != "pedestrian")
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def shortest_path_length(world_map: MapInfo, start: tuple[float, float],
                         goal: tuple[float, float], radius: float, resolution: float,
                         key: str | None = None) -> float:
    """Length [m] of the shortest path for a disc of ``radius`` [m] from ``start`` to within
    reach of ``goal`` on ``world_map`` (without its movable obstacles). When the grid has no
    such path (a start or goal hugging a wall closer than the grid resolves), the straight
    line, a lower bound of every path, is used. ``key`` names the map for the cache. The grid
    never exceeds MAX_GRID_CELLS cells: a larger world is planned at a coarser resolution."""
    # A world too large for a grid at ``resolution`` (a map of 5 m cells) is planned on a
    # coarser one: at most MAX_GRID_CELLS cells, as for the planners.
    width, height = world_map.size
    resolution = max(resolution, math.sqrt(width * height / MAX_GRID_CELLS))
    cache_key = None if key is None else (key, tuple(start), tuple(goal), radius, resolution)
    if cache_key is not None and cache_key in _cache:
        return _cache[cache_key]
    grid = ClearanceGrid.from_map(world_map.without_movable(), resolution,
                                  cap=radius + 2.0 * resolution)
    plan = astar(grid, start, goal, hard=radius, soft=radius, weight=0.0,
                 goal_radius=radius, start_escape=radius)
    straight = math.dist(start, goal)
    length = straight
    if plan.path is not None:
        length = max(straight, path_length(shortcut(grid, plan.path, radius)))
    if cache_key is not None:
        if len(_cache) >= MAX_CACHED:
            _cache.pop(next(iter(_cache)))
        _cache[cache_key] = length
    return length
