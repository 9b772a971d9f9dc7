"""A scenario's static geometry as an occupancy grid: what a prebuilt map of the arena would hold."""
from __future__ import annotations

import numpy as np

from ..planning.grid import ClearanceGrid
from ..planning.map import MapInfo
from .grid import FREE, OCCUPIED, OccupancyGrid
from .geometry import solid_cells

BORDER_CELLS = 2  # occupied cells kept outside the arena's interior, so its walls are on the map


def grid_from_map(world_map: MapInfo, resolution: float) -> OccupancyGrid:
    """Rasterise the arena and the map's obstacles at ``resolution`` [m].

    A cell is occupied when its centre lies within half a cell of an obstacle (so a wall thinner
    than a cell still leaves a closed line of occupied cells), or outside the arena's interior.
    The grid covers the interior plus ``BORDER_CELLS`` of wall on every side. A map read from a
    ROS map file (``world_map.grid``) is returned as it is when ``resolution`` is its own, and
    adds its solid cells (occupied or unknown) otherwise.
    """
    if not (np.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be > 0 (got {resolution})")
    own = world_map.grid
    if own is not None and abs(own.resolution - resolution) <= 1e-9 * resolution:
        return _with_obstacles(own, world_map)
    pad = BORDER_CELLS * resolution
    x0, y0 = world_map.origin
    width, height = world_map.size
    inner = ClearanceGrid((width + 2 * pad, height + 2 * pad), resolution, cap=resolution,
                          origin=(x0 - pad, y0 - pad))
    for polygon in world_map.polygons:
        inner.add_polygon(polygon.points)
    for circle in world_map.circles:
        inner.add_circle(circle.center, circle.radius)
    occupied = inner.clearance < 0.5 * resolution
    xs, ys = inner.xs, inner.ys
    outside = np.logical_or.outer((ys < y0) | (ys > y0 + height), (xs < x0) | (xs > x0 + width))
    data = np.where(occupied | outside, OCCUPIED, FREE).astype(np.int8)
    grid = OccupancyGrid(data, float(resolution), (x0 - pad, y0 - pad))
    if own is not None:  # the file's solid cells, sampled at this grid's cell centres
        row, col = own.cell_of(np.stack(np.meshgrid(xs, ys), axis=-1))
        on = own.inside(row, col)
        solid = np.zeros(data.shape, dtype=bool)
        solid[on] = solid_cells(own)[row[on], col[on]]
        data[solid] = OCCUPIED
    return grid


def _with_obstacles(own: OccupancyGrid, world_map: MapInfo) -> OccupancyGrid:
    """A ROS map's own grid, with the scenario's obstacles (those not from the map) on it."""
    extra = world_map.polygons[world_map.map_shapes:]
    if not extra and not world_map.circles:
        return own
    marks = ClearanceGrid(own.size, own.resolution, cap=own.resolution, origin=own.origin)
    marks.clearance[:] = marks.cap  # the map's edge is already in the map's own cells
    for polygon in extra:
        marks.add_polygon(polygon.points)
    for circle in world_map.circles:
        marks.add_circle(circle.center, circle.radius)
    data = np.array(own.data)
    data[marks.clearance[:own.rows, :own.cols] < 0.5 * own.resolution] = OCCUPIED
    return OccupancyGrid(data, own.resolution, own.origin)


def scenario_grid(config, resolution: float, movable: bool = False) -> OccupancyGrid:
    """The occupancy grid of a scenario's arena and fixed obstacles (``movable``: crates too)."""
    world_map = MapInfo.from_scenario(config)
    return grid_from_map(world_map if movable else world_map.without_movable(), resolution)
