"""Where the fixed world is, as marked cells: which points may have a fixed shape near them.

The substep gate asks pymunk, mover by mover, how far the nearest fixed shape is (a point
query). Most movers of a large fleet have none within reach; this index says which may, in
one array operation for all of them: every cell that a fixed shape's bounding box overlaps
is marked, and a point has no fixed shape within ``look`` [m] when no cell of the square of
half-width ``look`` about it is marked (a summed-area table answers that in four reads). It
only ever answers "maybe" too often, never "no" wrongly, so the gate's answers are the same.

The cells are built again when a shape comes or goes, and after :meth:`StaticCells.forget`
(the gate calls it when bodies were moved outside the physics: ``World.disturb``); a fixed
body moved by hand is not looked for at every test (that cost a microsecond per body).
"""
from __future__ import annotations

import math
from typing import Collection

import numba
import numpy as np
import pymunk

MAX_CELLS = 1 << 20  # cells of the grid at most (4 MB of counts)
MIN_CELL = 0.5  # [m] the finest cell: about a robot's size


class StaticCells:
    """The bounding boxes of ``space``'s shapes that belong to no body of ``moving`` (and are
    no sensors), as marked cells; built again when the Space's shapes change."""

    def __init__(self, space: pymunk.Space, moving: Collection[pymunk.Body]) -> None:
        self.space = space
        self._moving = moving
        self._key: tuple | None = None  # the shapes the cells were built from
        self._origin = (0.0, 0.0)  # [m] the grid's lower-left corner
        self._cell = 1.0  # [m]
        self._table = np.zeros((1, 1), dtype=np.int32)  # summed-area table of marked cells
        self._everywhere = False  # a shape without bounds: every point may be near it

    def near(self, xy: np.ndarray, look: np.ndarray) -> np.ndarray:
        """For each point of ``xy`` (n, 2) [m]: whether a fixed shape may lie within ``look``
        (n,) [m] of it (False: certainly none does)."""
        self._refresh()
        if self._everywhere:
            return np.ones(xy.shape[0], dtype=bool)
        near = np.empty(xy.shape[0], dtype=np.bool_)
        _near_cells(xy, look, self._table, self._origin[0], self._origin[1], self._cell, near)
        return near

    def forget(self) -> None:
        """Fixed bodies may have moved: the cells are built again at the next question."""
        self._key = None

    def _refresh(self) -> None:
        """Build the cells again if a shape came or went (or after :meth:`forget`)."""
        key = tuple(self.space.shapes)
        if key == self._key:
            return
        self._key = key
        boxes = []
        for shape in key:
            if shape.sensor or shape.body is None or shape.body in self._moving:
                continue
            bb = shape.cache_bb()
            boxes.append((bb.left, bb.bottom, bb.right, bb.top))
        self._build(np.array(boxes, dtype=float).reshape(-1, 4))

    def _build(self, boxes: np.ndarray) -> None:
        """Mark the cells each box (left, bottom, right, top) [m] overlaps."""
        self._everywhere = not np.isfinite(boxes).all()
        if boxes.shape[0] == 0 or self._everywhere:  # nothing fixed, or nothing to mark
            self._origin, self._cell = (0.0, 0.0), 1.0
            self._table = np.zeros((2, 2), dtype=np.int32)
            return
        left, bottom = float(boxes[:, 0].min()), float(boxes[:, 1].min())
        width = float(boxes[:, 2].max()) - left
        height = float(boxes[:, 3].max()) - bottom
        cell = max(MIN_CELL, math.sqrt(max(width * height, 1e-12) / MAX_CELLS))
        cols = int(width / cell) + 1
        rows = int(height / cell) + 1
        while cols * rows > MAX_CELLS:  # long thin worlds: coarser until it fits
            cell *= 1.5
            cols, rows = int(width / cell) + 1, int(height / cell) + 1
        grid = np.zeros((rows, cols), dtype=np.int32)
        i0 = np.floor((boxes[:, 0] - left) / cell).astype(np.intp)
        i1 = np.minimum(np.floor((boxes[:, 2] - left) / cell).astype(np.intp), cols - 1)
        j0 = np.floor((boxes[:, 1] - bottom) / cell).astype(np.intp)
        j1 = np.minimum(np.floor((boxes[:, 3] - bottom) / cell).astype(np.intp), rows - 1)
        for a, b, c, d in zip(j0.tolist(), j1.tolist(), i0.tolist(), i1.tolist()):
            grid[a:b + 1, c:d + 1] = 1
        table = np.zeros((rows + 1, cols + 1), dtype=np.int32)
        table[1:, 1:] = grid.cumsum(axis=0).cumsum(axis=1)
        self._origin, self._cell, self._table = (left, bottom), cell, table


@numba.njit(cache=True)
def _near_cells(xy: np.ndarray, look: np.ndarray, table: np.ndarray, left: float,
                bottom: float, cell: float, near: np.ndarray) -> None:
    """``near[k]``: whether a marked cell lies in the square of half-width ``look[k]`` [m]
    about ``xy[k]`` [m], or one cell beyond it (rounding at the cells' edges); True for a
    point that is not finite. ``table``: the cells' summed-area table, the grid's corner at
    (``left``, ``bottom``) [m], cells of ``cell`` [m]."""
    rows, cols = table.shape[0] - 1, table.shape[1] - 1
    for k in range(xy.shape[0]):
        x, y, r = xy[k, 0], xy[k, 1], look[k]
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(r)):
            near[k] = True
            continue
        i0 = min(max(math.floor((x - r - left) / cell) - 1, 0), cols)
        i1 = min(max(math.floor((x + r - left) / cell) + 2, 0), cols)
        j0 = min(max(math.floor((y - r - bottom) / cell) - 1, 0), rows)
        j1 = min(max(math.floor((y + r - bottom) / cell) + 2, 0), rows)
        near[k] = table[j1, i1] - table[j0, i1] - table[j1, i0] + table[j0, i0] > 0

