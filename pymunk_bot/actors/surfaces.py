"""The surfaces pedestrians keep away from, as arrays of pieces, and the wall force from them.

Every pymunk shape a walker feels is stored once as pieces in its body's frame: a circle is one
piece (a point with a radius), a segment one piece, a polygon its edges (closed: a point inside
it has a negative distance). The signed distance to a shape and its gradient are those of
``pymunk.Shape.point_query`` (Chipmunk's circle, segment and polygon queries). The fixed world
is read once, at the start, and binned in a grid of cells, each listing the shapes within reach
of it, so a walker looks at the few shapes near it even on a large map; moving shapes (robots,
crates) are read in their body's frame and placed each tick by their body's pose.

:func:`wall_forces` sums, for every walker, U0 / R exp(-gap / R) along each gradient over every
shape closer than the walker's reach (Helbing & Molnar 1995's wall repulsion; see
:mod:`.pedestrians`), compiled with numba.
"""
from __future__ import annotations

import math
from typing import Sequence

import numba
import numpy as np
import pymunk

from pymunk_bot.actors.clearance import CONTACT_MARGIN, SURFACE, Clearances, record

MAGIC_EPSILON = 1e-5  # [m] Chipmunk's: closer than this a query gives a normal, not p - closest
MAX_CELLS = 250_000  # the fixed world's lookup grid has at most this many cells ...
MAX_LISTED = 2_000_000  # ... and lists at most this many shapes over all of them


CLOSED, ROBOT = 1, 2  # flags of a shape: a polygon; a robot's (walkers may ignore robots)


class Surfaces:
    """Shapes as pieces in their bodies' frames (see the module doc).

    ``pieces`` (m, 4): each piece's ends ax, ay, bx, by [m] (a == b for a circle); ``shapes``
    (k, 4): the pieces start:stop of each shape, the index of its body in ``bodies`` and its
    flags (CLOSED, ROBOT); ``radius`` (k,) [m].
    """

    def __init__(self, shapes: Sequence[pymunk.Shape], robots: set) -> None:
        self.bodies: list[pymunk.Body] = []
        index: dict[pymunk.Body, int] = {}
        pieces: list[tuple[float, float, float, float]] = []
        rows: list[tuple[int, int, int, int]] = []
        radius: list[float] = []
        for shape in shapes:
            owner = shape.body
            ends = _pieces(shape)
            if owner is None or ends is None:
                continue
            if owner not in index:
                index[owner] = len(self.bodies)
                self.bodies.append(owner)
            flags = CLOSED * isinstance(shape, pymunk.Poly) + ROBOT * (owner in robots)
            rows.append((len(pieces), len(pieces) + len(ends), index[owner], flags))
            pieces.extend(ends)
            radius.append(float(shape.radius))
        self.pieces = np.array(pieces, dtype=float).reshape(-1, 4)
        self.shapes = np.array(rows, dtype=np.int64).reshape(-1, 4)
        self.radius = np.array(radius, dtype=float)
        # The kernels' lookup when there is no grid: every shape in one cell.
        self.one_cell = (np.array([0, len(radius)], dtype=np.int64),
                         np.arange(len(radius), dtype=np.int64), np.zeros(5))

    def __len__(self) -> int:
        return len(self.radius)

    def poses(self) -> np.ndarray:
        """Each body's x, y [m] and angle [rad] now, shape (bodies, 3)."""
        return np.array([(*b.position, b.angle) for b in self.bodies], dtype=float).reshape(-1, 3)

    def boxes(self) -> np.ndarray:
        """Each shape's bounding box (left, bottom, right, top) [m] at its body's pose now,
        radius included, shape (k, 4)."""
        poses = self.poses()
        out = np.empty((len(self), 4))
        for s, (start, stop, body, _) in enumerate(self.shapes.tolist()):
            x, y, angle = poses[body]
            c, sn = math.cos(angle), math.sin(angle)
            ends = self.pieces[start:stop].reshape(-1, 2)
            wx = x + c * ends[:, 0] - sn * ends[:, 1]
            wy = y + sn * ends[:, 0] + c * ends[:, 1]
            r = self.radius[s]
            out[s] = (wx.min() - r, wy.min() - r, wx.max() + r, wy.max() + r)
        return out


def _pieces(shape: pymunk.Shape) -> list[tuple[float, float, float, float]] | None:
    """A shape's pieces (ends a, b) in its body's frame, or None for a kind it has not."""
    if isinstance(shape, pymunk.Circle):
        x, y = shape.offset
        return [(x, y, x, y)]
    if isinstance(shape, pymunk.Segment):
        return [(shape.a.x, shape.a.y, shape.b.x, shape.b.y)]
    if isinstance(shape, pymunk.Poly):
        v = [(float(p.x), float(p.y)) for p in shape.get_vertices()]
        return [(v[i - 1][0], v[i - 1][1], v[i][0], v[i][1]) for i in range(len(v))]
    return None


class CellIndex:
    """For a fixed set of shapes: which of them each cell of a grid can reach.

    Cell (i, j) covers [x0 + j size, x0 + (j + 1) size) x [y0 + i size, ...) and lists every
    shape whose bounding box, grown by ``reach`` [m], meets it: a point of the cell is closer
    than ``reach`` to no other shape. Points outside the grid reach nothing."""

    def __init__(self, boxes: np.ndarray, reach: float) -> None:
        boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
        grown = boxes + np.array([-reach, -reach, reach, reach])
        if not len(grown):
            grown = np.zeros((1, 4))
        x0, y0 = float(grown[:, 0].min()), float(grown[:, 1].min())
        width = float(grown[:, 2].max()) - x0
        height = float(grown[:, 3].max()) - y0
        size = max(reach, 1e-3)  # [m]
        spans = grown[:len(boxes)]
        while math.ceil(width / size) * math.ceil(height / size) > MAX_CELLS or float(
                (((spans[:, 2] - spans[:, 0]) // size + 2)
                 * ((spans[:, 3] - spans[:, 1]) // size + 2)).sum()) > MAX_LISTED:
            size *= 2.0  # (a bound on each shape's cells: its span's, plus a cell each way)
        self.origin = np.array([x0, y0])  # [m]
        self.size = size  # [m]
        self.cols = max(1, math.ceil(width / size))
        self.rows = max(1, math.ceil(height / size))
        lists: list[list[int]] = [[] for _ in range(self.rows * self.cols)]
        for s, (left, bottom, right, top) in enumerate(spans.tolist()):
            c0, c1 = self._span(left, right, x0, self.cols)
            r0, r1 = self._span(bottom, top, y0, self.rows)
            for row in range(r0, r1 + 1):
                for col in range(c0, c1 + 1):
                    lists[row * self.cols + col].append(s)
        self.start = np.zeros(len(lists) + 1, dtype=np.int64)
        self.start[1:] = np.cumsum([len(cell) for cell in lists])
        self.shapes = np.array([s for cell in lists for s in cell], dtype=np.int64)
        self.grid = np.array([x0, y0, size, self.cols, self.rows], dtype=float)

    def _span(self, lo: float, hi: float, origin: float, count: int) -> tuple[int, int]:
        first = min(max(int((lo - origin) // self.size), 0), count - 1)
        last = min(max(int((hi - origin) // self.size), 0), count - 1)
        return first, last


def wall_forces(surfaces: Surfaces, poses: np.ndarray, cells: CellIndex | None,
                pos: np.ndarray, walkers: np.ndarray, reacts: np.ndarray,
                out: np.ndarray, clearances: Clearances) -> None:
    """Add to ``out`` (n, 2) each walker's wall repulsion per unit mass [m/s^2] from every
    shape of ``surfaces`` (bodies at ``poses``) nearer than its reach from its centre ``pos``:
    U0 / R exp(-max(d - excess, 0) / R) along the shape's gradient, d its signed distance [m].
    ``walkers`` (n, 5): reach [m], excess [m], U0 [m^2/s^2], R [m] and radius [m] of each.
    ``cells``: the lookup grid of a fixed set (None: every shape is looked at). Walkers that
    do not ``react`` skip robots. Each of those shapes a walker could reach in a step is
    recorded in ``clearances``."""
    if len(surfaces) and len(pos):
        start, listed, grid = _lookup(surfaces, cells)
        _wall_forces(surfaces.pieces, surfaces.shapes, surfaces.radius, poses, start, listed,
                     grid, pos, walkers, reacts, out, clearances.reach, clearances.near,
                     clearances.count)


def _lookup(surfaces: Surfaces, cells: CellIndex | None
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' view of a lookup grid (cells' starts, their shapes, the grid's origin,
    cell size and shape): every shape in one cell when there is none."""
    return surfaces.one_cell if cells is None else (cells.start, cells.shapes, cells.grid)


@numba.njit(cache=True, nogil=True)
def _cell(px: float, py: float, grid: np.ndarray) -> int:
    """The lookup cell of (px, py), -1 outside the grid (grid size 0: the only cell)."""
    size = grid[2]
    if size <= 0.0:
        return 0
    col = int(math.floor((px - grid[0]) / size))
    row = int(math.floor((py - grid[1]) / size))
    if col < 0 or row < 0 or col >= grid[3] or row >= grid[4]:
        return -1
    return row * int(grid[3]) + col


@numba.njit(cache=True, nogil=True)
def shape_query(px: float, py: float, pieces: np.ndarray, start: int, stop: int,
                radius: float, closed: bool, pose: np.ndarray) -> tuple[float, float, float]:
    """Signed distance [m] from (px, py) to one shape (pieces start:stop in its body's frame,
    body at ``pose``) and the unit gradient (gx, gy), as ``pymunk.Shape.point_query`` gives
    them."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    best, cx, cy, nx, ny = math.inf, 0.0, 0.0, 0.0, 1.0
    outside = not closed
    for k in range(start, stop):
        ax = pose[0] + c * pieces[k, 0] - s * pieces[k, 1]
        ay = pose[1] + s * pieces[k, 0] + c * pieces[k, 1]
        bx = pose[0] + c * pieces[k, 2] - s * pieces[k, 3]
        by = pose[1] + s * pieces[k, 2] + c * pieces[k, 3]
        ex, ey = bx - ax, by - ay
        length2 = ex * ex + ey * ey
        t = 0.0
        if length2 > 0.0:
            t = min(max(((px - ax) * ex + (py - ay) * ey) / length2, 0.0), 1.0)
        qx, qy = ax + t * ex, ay + t * ey
        d = math.sqrt((px - qx) ** 2 + (py - qy) ** 2)
        length = math.sqrt(length2)
        # Chipmunk's normal of an edge a -> b (outward for its counter-clockwise polygons)
        ux, uy = (ey / length, -ex / length) if length > 0.0 else (0.0, 1.0)
        if closed and ux * (px - bx) + uy * (py - by) > 0.0:
            outside = True
        if d < best:
            best, cx, cy, nx, ny = d, qx, qy, ux, uy
    signed = best if outside else -best
    if best > MAGIC_EPSILON:
        return signed - radius, (px - cx) / signed, (py - cy) / signed
    return signed - radius, nx, ny  # on the surface: its normal ((0, 1) at a circle's centre)


@numba.njit(cache=True, nogil=True)
def _wall_forces(pieces: np.ndarray, shapes: np.ndarray, radius: np.ndarray, poses: np.ndarray,
                 cell_start: np.ndarray, cell_shapes: np.ndarray, grid: np.ndarray,
                 pos: np.ndarray, walkers: np.ndarray, reacts: np.ndarray,
                 out: np.ndarray, step_reach: np.ndarray, near: np.ndarray,
                 count: np.ndarray) -> None:  # pragma: no cover - compiled
    for i in range(len(pos)):
        px, py = pos[i, 0], pos[i, 1]
        cell = _cell(px, py, grid)
        if cell < 0:
            continue
        reach, excess, strength, wall_range = walkers[i, 0], walkers[i, 1], walkers[i, 2], \
            walkers[i, 3]
        for k in range(cell_start[cell], cell_start[cell + 1]):
            s = cell_shapes[k]
            flags = shapes[s, 3]
            if flags & ROBOT and not reacts[i]:
                continue
            d, gx, gy = shape_query(px, py, pieces, shapes[s, 0], shapes[s, 1], radius[s],
                                    flags & CLOSED != 0, poses[shapes[s, 2]])
            if d - walkers[i, 4] - CONTACT_MARGIN < step_reach[i]:
                record(near, count, i, d - walkers[i, 4], -gx, -gy, SURFACE)
            if d >= reach:
                continue
            push = strength / wall_range * math.exp(-max(d - excess, 0.0) / wall_range)
            out[i, 0] += push * gx
            out[i, 1] += push * gy


def nearest_walls(surfaces: Surfaces, poses: np.ndarray, cells: CellIndex | None,
                  points: np.ndarray, reach: np.ndarray, out: np.ndarray,
                  count: np.ndarray) -> None:
    """Merge into ``out`` (k, K, 3), nearest first, and ``count`` (k,) the shapes of
    ``surfaces`` other than robots' nearer to each of ``points`` (k, 2) than its ``reach`` [m]:
    (signed distance [m], gradient x, gradient y), the K nearest kept (ties by gradient)."""
    if len(surfaces) and len(points):
        start, listed, grid = _lookup(surfaces, cells)
        _nearest_walls(surfaces.pieces, surfaces.shapes, surfaces.radius, poses, start, listed,
                       grid, points, reach, out, count)


@numba.njit(cache=True, nogil=True)
def _nearest_walls(pieces: np.ndarray, shapes: np.ndarray, radius: np.ndarray,
                   poses: np.ndarray, cell_start: np.ndarray, cell_shapes: np.ndarray,
                   grid: np.ndarray, points: np.ndarray, reach: np.ndarray, out: np.ndarray,
                   count: np.ndarray) -> None:  # pragma: no cover - compiled
    keep = out.shape[1]
    for a in range(len(points)):
        px, py = points[a, 0], points[a, 1]
        cell = _cell(px, py, grid)
        if cell < 0:
            continue
        for k in range(cell_start[cell], cell_start[cell + 1]):
            s = cell_shapes[k]
            if shapes[s, 3] & ROBOT:
                continue
            d, gx, gy = shape_query(px, py, pieces, shapes[s, 0], shapes[s, 1], radius[s],
                                    shapes[s, 3] & CLOSED != 0, poses[shapes[s, 2]])
            if d >= reach[a]:
                continue
            j = count[a]  # insertion: (d, gx, gy) after every row that is not larger
            while j > 0 and (d, gx, gy) < (out[a, j - 1, 0], out[a, j - 1, 1], out[a, j - 1, 2]):
                if j < keep:
                    out[a, j] = out[a, j - 1]
                j -= 1
            if j < keep:
                out[a, j, 0], out[a, j, 1], out[a, j, 2] = d, gx, gy
                count[a] = min(count[a] + 1, keep)
