"""A scenario's static geometry as an occupancy grid: what a prebuilt map of the arena would hold."""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.maps.grid import FREE, OCCUPIED, OccupancyGrid
from pymunk_bot.maps.outlines import solid_cells

BORDER_CELLS = 2  # occupied cells kept outside the arena's interior, so its walls are on the map
THIN = math.sqrt(2.0)  # [cells] obstacles narrower than this also get their centre line marked


def grid_from_map(world_map: MapInfo, resolution: float) -> OccupancyGrid:
    """Rasterise the arena and the map's obstacles at ``resolution`` [m].

    A cell is occupied when its centre lies inside an obstacle or outside the arena's interior:
    the same unbiased rule for both, so an occupied region's edge is the true surface to within
    half a cell either way. Obstacles too thin for that rule to leave a closed line of cells
    (narrower than ``THIN`` cells: thin walls, map segments, small posts) also get the cells
    along their centre line (a post: the cell holding its centre).
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
    occupied = _solid(inner, world_map.polygons, world_map.circles)
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
    data = np.array(own.data)
    data[_solid(marks, extra, world_map.circles)[:own.rows, :own.cols]] = OCCUPIED
    return OccupancyGrid(data, own.resolution, own.origin)


def scenario_grid(config, resolution: float, movable: bool = False) -> OccupancyGrid:
    """The occupancy grid of a scenario's arena and fixed obstacles (``movable``: crates too)."""
    world_map = MapInfo.from_scenario(config)
    return grid_from_map(world_map if movable else world_map.without_movable(), resolution)


def _solid(grid: ClearanceGrid, polygons, circles) -> np.ndarray:
    """Boolean (rows, cols): cells of ``grid`` whose centre is inside a polygon or circle, plus
    the centre line of every one too thin to be seen by its cell centres."""
    res = grid.resolution
    for polygon in polygons:
        grid.add_polygon(polygon.points)
    for circle in circles:
        grid.add_circle(circle.center, circle.radius)
    solid = grid.clearance <= 0.0  # add_* set 0 inside a shape, a positive distance outside
    lines = [line for line in map(_thin_centre_line, (p.points for p in polygons),
                                  [THIN * res] * len(polygons)) if line is not None]
    lines += [(np.asarray(c.center, float), np.asarray(c.center, float)) for c in circles
              if 2.0 * c.radius < THIN * res]
    for a, b in lines:  # sampled at a quarter cell: an 8-connected line of cells
        n = max(2, math.ceil(float(np.hypot(*(b - a))) / (0.25 * res)) + 1)
        pts = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
        rows, cols = grid.cells_of(pts[:, 0], pts[:, 1])
        on = grid.inside(pts[:, 0], pts[:, 1])
        solid[rows[on], cols[on]] = True
    return solid


def _thin_centre_line(points: np.ndarray, thin: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The centre line (a, b) of a convex outline narrower than ``thin`` [m], else None.

    The narrowest direction is across one of the outline's edges (rotating calipers); the line
    runs along that edge's direction, halfway across the outline's width.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if pts.shape[0] == 1:
        return pts[0], pts[0]
    edges = np.roll(pts, -1, axis=0) - pts
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    if not (lengths > 0).any():
        return pts[0], pts[0]
    along = edges[lengths > 0] / lengths[lengths > 0, None]
    across = np.column_stack([-along[:, 1], along[:, 0]])
    depth = pts @ across.T  # (points, directions)
    widths = depth.max(axis=0) - depth.min(axis=0)
    k = int(np.argmin(widths))
    if widths[k] >= thin:
        return None
    s = pts @ along[k]
    middle = 0.5 * (depth[:, k].max() + depth[:, k].min())
    return (s.min() * along[k] + middle * across[k], s.max() * along[k] + middle * across[k])
