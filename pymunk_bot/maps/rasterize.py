"""A scenario's static geometry as an occupancy grid: what a prebuilt map of the arena would hold."""
from __future__ import annotations

import numpy as np

from ..planning.grid import ClearanceGrid
from ..planning.map import MapInfo
from .grid import FREE, OCCUPIED, OccupancyGrid

BORDER_CELLS = 2  # occupied cells kept outside the arena's interior, so its walls are on the map


def grid_from_map(world_map: MapInfo, resolution: float) -> OccupancyGrid:
    """Rasterise the arena and the map's obstacles at ``resolution`` [m].

    A cell is occupied when its centre lies within half a cell of an obstacle (so a wall thinner
    than a cell still leaves a closed line of occupied cells), or outside the arena's interior.
    The grid covers the interior plus ``BORDER_CELLS`` of wall on every side.
    """
    if not (np.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be > 0 (got {resolution})")
    pad = BORDER_CELLS * resolution
    width, height = world_map.size
    inner = ClearanceGrid((width + 2 * pad, height + 2 * pad), resolution, cap=resolution)
    shifted = MapInfo(
        inner.size,
        tuple(type(p)(np.asarray(p.points) + pad, p.movable) for p in world_map.polygons),
        tuple(type(c)((c.center[0] + pad, c.center[1] + pad), c.radius, c.movable)
              for c in world_map.circles))
    for polygon in shifted.polygons:
        inner.add_polygon(polygon.points)
    for circle in shifted.circles:
        inner.add_circle(circle.center, circle.radius)
    occupied = inner.clearance < 0.5 * resolution
    xs = inner.xs - pad
    ys = inner.ys - pad
    outside = np.logical_or.outer((ys < 0) | (ys > height), (xs < 0) | (xs > width))
    data = np.where(occupied | outside, OCCUPIED, FREE).astype(np.int8)
    return OccupancyGrid(data, float(resolution), (-pad, -pad))


def scenario_grid(config, resolution: float, movable: bool = False) -> OccupancyGrid:
    """The occupancy grid of a scenario's arena and fixed obstacles (``movable``: crates too)."""
    world_map = MapInfo.from_scenario(config)
    return grid_from_map(world_map if movable else world_map.without_movable(), resolution)
