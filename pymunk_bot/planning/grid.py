"""A clearance grid: the distance from each cell centre to the nearest obstacle, built with numpy.

Instead of a 0/1 occupancy image plus a distance transform we compute, for every cell centre,
the exact Euclidean distance to the nearest obstacle surface (0 inside one), capped at ``cap``.
Each obstacle only touches the cells within ``cap`` of its bounding box, so a map of a few
hundred obstacles rasterises in milliseconds. Inflation is then a threshold: a disc robot of
radius r fits wherever the clearance is at least r.
"""
from __future__ import annotations

import math
from typing import overload

import numba
import numpy as np

from pymunk_bot.planning.map import MapInfo


def _segment_distances(px: np.ndarray, py: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance from each (px, py) to the closed outline ``points`` (edges only)."""
    best = np.full(px.shape, np.inf)
    n = len(points)
    for i in range(n):
        ax, ay = points[i]
        bx, by = points[(i + 1) % n]
        ex, ey = bx - ax, by - ay
        length2 = ex * ex + ey * ey
        t = ((px - ax) * ex + (py - ay) * ey) / length2 if length2 > 0 else np.zeros(px.shape)
        t = np.clip(t, 0.0, 1.0)
        np.minimum(best, np.hypot(px - (ax + t * ex), py - (ay + t * ey)), out=best)
    return best


def points_in_polygon(px: np.ndarray, py: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Even-odd rule for many points at once (either winding, concave allowed)."""
    inside = np.zeros(px.shape, dtype=bool)
    n = len(points)
    for i in range(n):
        x1, y1 = points[i]
        x2, y2 = points[(i + 1) % n]
        if y1 == y2:
            continue  # a horizontal edge never crosses the horizontal ray
        crosses = (y1 > py) != (y2 > py)
        x_at = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
        inside ^= crosses & (px < x_at)
    return inside


class ClearanceGrid:
    """Cells of ``resolution`` metres covering the arena; ``clearance[row, col]`` in metres.

    Row i, column j has its centre at ``origin + ((j + 0.5) * res, (i + 0.5) * res)``.
    """

    def __init__(self, size: tuple[float, float], resolution: float, cap: float,
                 origin: tuple[float, float] = (0.0, 0.0)) -> None:
        if not (resolution > 0 and cap > 0):
            raise ValueError("resolution and cap must be > 0")
        self.size = (float(size[0]), float(size[1]))
        self.origin = (float(origin[0]), float(origin[1]))  # [m] the arena's lower-left corner
        self.resolution = float(resolution)
        self.cap = float(cap)  # [m] clearances beyond this read as this
        self.cols = max(1, math.ceil(self.size[0] / resolution - 1e-9))
        self.rows = max(1, math.ceil(self.size[1] / resolution - 1e-9))
        ox, oy = self.origin
        self.xs = ox + (np.arange(self.cols) + 0.5) * resolution  # cell centre x [m]
        self.ys = oy + (np.arange(self.rows) + 0.5) * resolution  # cell centre y [m]
        width, height = self.size
        to_wall_x = np.minimum(self.xs - ox, ox + width - self.xs)
        to_wall_y = np.minimum(self.ys - oy, oy + height - self.ys)
        self.clearance = np.minimum(np.minimum.outer(to_wall_y, to_wall_x), self.cap)
        np.maximum(self.clearance, 0.0, out=self.clearance)

    @classmethod
    def from_map(cls, world_map: MapInfo, resolution: float, cap: float) -> "ClearanceGrid":
        """Rasterise a map's arena and every obstacle in it."""
        grid = cls(world_map.size, resolution, cap, world_map.origin)
        for polygon in world_map.polygons:
            grid.add_polygon(polygon.points)
        for circle in world_map.circles:
            grid.add_circle(circle.center, circle.radius)
        return grid

    def copy(self) -> "ClearanceGrid":
        twin = object.__new__(ClearanceGrid)
        twin.__dict__.update(self.__dict__)
        twin.clearance = self.clearance.copy()
        return twin

    # ------------------------------------------------------------------ rasterising
    def _window(self, x0: float, y0: float, x1: float, y1: float):
        """Index slices of the cells whose centres lie within ``cap`` of a bounding box."""
        res, cap = self.resolution, self.cap
        ox, oy = self.origin
        c0 = max(0, math.floor((x0 - ox - cap) / res - 0.5))
        c1 = min(self.cols, math.ceil((x1 - ox + cap) / res + 0.5))
        r0 = max(0, math.floor((y0 - oy - cap) / res - 0.5))
        r1 = min(self.rows, math.ceil((y1 - oy + cap) / res + 0.5))
        if c0 >= c1 or r0 >= r1:
            return None
        return slice(r0, r1), slice(c0, c1)

    def add_polygon(self, points: np.ndarray) -> None:
        """Lower the clearance around a filled polygon."""
        points = np.asarray(points, dtype=float)
        window = self._window(*points.min(axis=0), *points.max(axis=0))
        if window is None:
            return
        rows, cols = window
        px, py = np.meshgrid(self.xs[cols], self.ys[rows])
        distance = _segment_distances(px, py, points)
        distance[points_in_polygon(px, py, points)] = 0.0
        np.minimum(self.clearance[rows, cols], distance, out=self.clearance[rows, cols])

    def add_circle(self, center, radius: float) -> None:
        """Lower the clearance around a filled disc (radius 0: a point obstacle)."""
        cx, cy = float(center[0]), float(center[1])
        window = self._window(cx - radius, cy - radius, cx + radius, cy + radius)
        if window is None:
            return
        rows, cols = window
        distance = np.sqrt(np.add.outer((self.ys[rows] - cy) ** 2, (self.xs[cols] - cx) ** 2))
        np.maximum(distance - radius, 0.0, out=distance)
        np.minimum(self.clearance[rows, cols], distance, out=self.clearance[rows, cols])

    def add_points(self, points: np.ndarray) -> None:
        """Lower the clearance around point obstacles (e.g. LiDAR returns), shape (n, 2)."""
        for x, y in np.asarray(points, dtype=float).reshape(-1, 2):
            self.add_circle((x, y), 0.0)

    # ------------------------------------------------------------------ look-ups
    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell containing a point, clamped to the grid."""
        col = min(self.cols - 1, max(0, math.floor((x - self.origin[0]) / self.resolution)))
        row = min(self.rows - 1, max(0, math.floor((y - self.origin[1]) / self.resolution)))
        return row, col

    def center_of(self, row: int, col: int) -> tuple[float, float]:
        return (self.origin[0] + (col + 0.5) * self.resolution,
                self.origin[1] + (row + 0.5) * self.resolution)

    @overload
    def inside(self, x: float, y: float) -> bool: ...
    @overload
    def inside(self, x: np.ndarray, y: np.ndarray) -> np.ndarray: ...

    def inside(self, x: float | np.ndarray, y: float | np.ndarray) -> bool | np.ndarray:
        """Which points lie within the arena (boundary included)."""
        ox, oy = self.origin
        return (x >= ox) & (x <= ox + self.size[0]) & (y >= oy) & (y <= oy + self.size[1])

    def cells_of(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of the cells containing many points, clamped to the grid."""
        res = self.resolution
        cols = np.clip(np.floor((x - self.origin[0]) / res).astype(int), 0, self.cols - 1)
        rows = np.clip(np.floor((y - self.origin[1]) / res).astype(int), 0, self.rows - 1)
        return rows, cols

    def segment_clearance(self, a, b) -> float:
        """Smallest cell clearance along the straight segment a-b (sampled at res/2)."""
        return float(segment_clearance(self.clearance, self.origin[0], self.origin[1],
                                       self.size[0], self.size[1], self.resolution,
                                       float(a[0]), float(a[1]), float(b[0]), float(b[1])))


@numba.njit(cache=True, nogil=True)
def segment_clearance(clearance: np.ndarray, ox: float, oy: float, width: float, height: float,
                      resolution: float, ax: float, ay: float, bx: float, by: float
                      ) -> float:  # pragma: no cover - compiled
    """Smallest cell clearance [m] along the segment a-b, sampled every res/2 or closer (0 if
    a sample leaves the arena): :meth:`ClearanceGrid.segment_clearance`, callable from other
    compiled code (plan guidance's lookahead point, every control step)."""
    n = max(2, math.ceil(math.hypot(bx - ax, by - ay) / (0.5 * resolution)) + 1)
    rows, cols = clearance.shape
    lowest = np.inf
    for k in range(n):
        t = k / (n - 1)
        x, y = ax + t * (bx - ax), ay + t * (by - ay)
        if not (ox <= x <= ox + width and oy <= y <= oy + height):
            return 0.0
        col = min(cols - 1, max(0, math.floor((x - ox) / resolution)))
        row = min(rows - 1, max(0, math.floor((y - oy) / resolution)))
        lowest = min(lowest, clearance[row, col])
    return lowest
