"""``world.map``: resolve the map file of a scenario, load it once, place robots and goals on it.

A relative ``map`` path is relative to the scenario file's directory (to the current directory
for data that came from no file, e.g. ``Simulation.from_dict``). ``size`` and ``map`` exclude
each other: with a map, the arena is the map's extent (the world frame is the map's frame, so
x0, y0 may be negative), and ``world.size`` is filled in with the extent's width and height.

Maps are cached by (resolved path, modification time, scale): a scenario parsed many times (a
batch of seeds, a reset) reads and traces its map once per process; editing the file reloads it.
"""
from __future__ import annotations

import functools
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from pymunk_bot.config.errors import ScenarioError

MAX_EXTENT = 1e4  # [m] a map's width or height, as any arena side (types.Length)
_CACHED_MAPS = 8


class _MapProblem(Exception):
    """A robot, goal or waypoint that the map rules out."""


def base_dir(source: str) -> Path:
    """Where a scenario's relative paths start: its file's directory, else the current one."""
    path = Path(source)
    return path.resolve().parent if source and path.is_file() else Path.cwd()


def attach_map(config: Any, source: str, node: Any = None) -> Any:
    """Check ``size`` / ``map`` / ``map_scale`` of ``config`` (a ScenarioConfig, whose module
    calls this one), load the map and return the config with the map
    resolved and ``world.size`` set to its extent (the config itself when there is no map)."""
    from pymunk_bot.config.yaml_source import line_of

    world = config.world

    def fail(key: str, problem: str) -> ScenarioError:
        return ScenarioError(source, f"world.{key}", problem, line_of(node, ("world", key)))

    if world.map is None:
        if world.size is None:
            raise ScenarioError(source, "world.size", "required (the arena's width and height "
                                "[m]), unless `world.map` gives a map file",
                                line_of(node, ("world",)))
        if world.map_scale is not None:
            raise fail("map_scale", "applies to `world.map` SVG plans only (there is no map)")
        return config
    if world.size is not None:
        raise fail("size", "give `size` or `map`, not both: with a map, the arena is the map's "
                           "extent")
    if not world.map.strip():
        raise fail("map", "must name a map file (.yaml/.yml ROS map or .svg plan)")
    path = Path(world.map).expanduser()
    if not path.is_absolute():
        path = base_dir(source) / path
    try:
        geometry = _load(str(path.resolve()), _mtime(path), world.map_scale, source)
    except ScenarioError as exc:
        line = line_of(node, ("world", exc.path.split(".")[-1])) \
            if exc.path.startswith("world.") else None
        raise ScenarioError(exc.source, exc.path, exc.problem, exc.line or line) from None
    width, height = geometry.size
    if not (0 < width <= MAX_EXTENT and 0 < height <= MAX_EXTENT):
        raise fail("map", f"the map is {width:g} x {height:g} m; each side must be at most "
                          f"{MAX_EXTENT:g} m")
    sized = world.with_map_path(str(path.resolve()), (float(width), float(height)))
    return config.model_copy(update={"world": sized})


def map_geometry(world: Any) -> Any:
    """The loaded map of a world that ``attach_map`` resolved (from the cache when unchanged)."""
    path = world.map_path
    if path is None:  # a WorldConfig built by hand: resolve against the current directory
        if world.map is None:
            raise ValueError("the world has no map")
        path = str(Path(world.map).expanduser().resolve())
    return _load(path, _mtime(Path(path)), world.map_scale, "<world.map>")


def _mtime(path: Path) -> int:
    try:
        return os.stat(path).st_mtime_ns
    except OSError:
        return -1  # the loader reports the missing file


def _load(path: str, mtime: int, scale: float | None, source: str) -> Any:
    try:
        return _cached(path, mtime, scale)
    except ScenarioError as exc:
        # The cached loader names no scenario: put the scenario's name on its error.
        raise ScenarioError(source, exc.path or "world.map", exc.problem, exc.line) from None


@functools.lru_cache(maxsize=_CACHED_MAPS)
def _cached(path: str, mtime: int, scale: float | None) -> Any:
    from pymunk_bot.maps.files import load_world_map

    return load_world_map(path, scale, source="<map>", key_path="world.map")


# ---------------------------------------------------------------------------- placement checks


def disc_problem(geometry: Any, x: float, y: float, radius: float) -> str | None:
    """Why a disc of ``radius`` [m] at (x, y) [m] cannot be on the map, or None when it fits."""
    from pymunk_bot.maps.outlines import free_disc

    x0, y0, x1, y1 = geometry.extent
    if not (x0 + radius <= x <= x1 - radius and y0 + radius <= y <= y1 - radius):
        return (f"({x:g}, {y:g}) is not inside the map's extent "
                f"[{x0:g}, {x1:g}] x [{y0:g}, {y1:g}] (world.map)")
    reach = max(radius, 1e-9)
    if free_disc(geometry, x, y, reach):
        return None
    grid = geometry.grid
    if grid is not None:
        cells = _cells_within(grid, x, y, reach)
        if cells is not None and (grid.data[cells] < 0).any() \
                and not geometry.solid[cells][grid.data[cells] >= 0].any():
            return (f"({x:g}, {y:g}) is on an unknown cell of world.map (unknown space counts "
                    "as solid)")
        return f"({x:g}, {y:g}) is on an occupied cell of world.map"
    return f"({x:g}, {y:g}) is inside a wall or obstacle of world.map"


def _cells_within(grid: Any, x: float, y: float, radius: float) -> Any:
    """Index (rows, cols) of the cells whose square lies within ``radius`` of (x, y)."""
    res = grid.resolution
    ox, oy = grid.origin
    c0 = max(0, math.floor((x - radius - ox) / res))
    c1 = min(grid.cols, math.floor((x + radius - ox) / res) + 1)
    r0 = max(0, math.floor((y - radius - oy) / res))
    r1 = min(grid.rows, math.floor((y + radius - oy) / res) + 1)
    if c0 >= c1 or r0 >= r1:
        return None
    cx = ox + (np.arange(c0, c1) + 0.5) * res
    cy = oy + (np.arange(r0, r1) + 0.5) * res
    dx = np.maximum(np.abs(cx - x) - 0.5 * res, 0.0)
    dy = np.maximum(np.abs(cy - y) - 0.5 * res, 0.0)
    rows, cols = np.nonzero(np.add.outer(dy * dy, dx * dx) < radius * radius)
    return rows + r0, cols + c0


__all__ = ["attach_map", "base_dir", "disc_problem", "map_geometry"]
