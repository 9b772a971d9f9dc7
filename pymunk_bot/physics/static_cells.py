"""Where the fixed world is, as marked cells: which points may have a fixed shape near them.

The substep gate asks pymunk, mover by mover, how far the nearest fixed shape is (a point
query). Most movers of a large fleet have none within reach; this index says which may, in
one compiled pass for all of them: every cell that a fixed shape covers (its outline grown by
its rounding radius, shapely's test of each cell of its bounding box) is marked, and a point
has no fixed shape within ``look`` [m] when no cell of the square of half-width ``look`` about
it is marked (a summed-area table answers that in four reads). It only ever answers "maybe"
too often (by at most a cell), never "no" wrongly, so the gate's answers are the same.

The cells are built at first, and again by :meth:`StaticCells.refresh` when a shape came or
went since, or after :meth:`StaticCells.forget` (the gate calls it when bodies were moved
outside the physics: ``World.disturb``; a fixed body moved by hand is not looked for at every
test, which cost a microsecond per body). The Space's shapes are compared only when the
world's ``fixed_version`` changed (someone was handed the Space, or disturbed the world):
comparing them at every test cost 34 us on the real warehouse map. Where the fixed shapes
are others that lie where the old ones did (a run rebuilt by a reset, in a new Space:
:meth:`StaticCells.watching`), the cells stand: building them was half of a simple scenario's
reset (3-11 ms). The substep gate refreshes before each of its tests, and when it is asked
which robots may step apart (physics/apart.py).
"""
from __future__ import annotations

import math
from typing import Callable, Collection, Sequence

import numba
import numpy as np
import pymunk
import shapely

_EVERY_SHAPE = pymunk.ShapeFilter()  # what pymunk is asked about: every shape
MAX_CELLS = 1 << 20  # cells of the grid at most (4 MB of counts)
MIN_CELL = 0.1  # [m] the finest cell: how much farther than asked "maybe" may reach
# [m] added to every distance asked: far above the rounding of coordinates (1e-13 m at 1 km),
# so a box point within the distance asked is always inside the square of cells read.
SLACK = 1e-6
# [m] what every fixed shape's outline is grown by before it marks cells: GEOS's arithmetic
# and Chipmunk's may differ in the last bits of a point on the outline.
OUTLINE_SLACK = 1e-6
# Segments per quarter circle of shapely's round buffers. Their vertices lie on the circle and
# the chords between them sag inside it by up to 1 - cos(pi / (4 * QUAD_SEGS)) of the radius
# (1.2 mm a metre at 16): each buffer is grown by that, so that it covers the round shape.
QUAD_SEGS = 16
_SAG = 1.0 / math.cos(math.pi / (4 * QUAD_SEGS))


class StaticCells:
    """The cells that ``space``'s shapes cover, those that belong to no body of ``moving`` and
    are no sensors; built again when the Space's shapes change (:meth:`refresh`)."""

    def __init__(self, space: pymunk.Space, moving: Collection[pymunk.Body],
                 version: Callable[[], int] | None = None) -> None:
        """``version()``: a count that changes whenever fixed shapes may have come, gone or
        moved (``World.fixed_version``); without it, every :meth:`refresh` compares the
        Space's shapes."""
        self.space = space
        self._moving = moving
        self._version = version
        self._seen: int | None = None  # the version the cells were checked at
        self._key: tuple | None = None  # the Space's shapes when the cells were last checked
        self._fixed: list[pymunk.Shape] | None = None  # the fixed shapes the cells were built from
        self._outline: list[tuple] | None = None  # what they cover (_outline_of)
        self._origin = (0.0, 0.0)  # [m] the grid's lower-left corner
        self._cell = 1.0  # [m]
        self._table = np.zeros((1, 1), dtype=np.int32)  # summed-area table of marked cells
        self._everywhere = False  # a shape without bounds: every point may be near it
        self._loose = False  # a shape of a kind not known here marked a box of many cells
        self.refresh()

    def near(self, xy: np.ndarray, look: np.ndarray) -> np.ndarray:
        """For each point of ``xy`` (n, 2) [m]: whether a fixed shape may lie within ``look``
        (n,) [m] of it (False: certainly none does), as of the last :meth:`refresh`."""
        if self._everywhere:
            return np.ones(xy.shape[0], dtype=bool)
        near = np.empty(xy.shape[0], dtype=np.bool_)
        _near_cells(xy, look, self._table, self._origin[0], self._origin[1], self._cell, near)
        return near

    def clearance(self, xy: np.ndarray, most: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For each point of ``xy`` (n, 2) [m]: a distance [m] within which no fixed shape
        lies, at most ``most`` (n,) [m], and one within which a fixed shape lies (inf: none
        found within ``most``): the cells tell the nearest shape's distance to within a cell
        or two."""
        out, within = np.empty(xy.shape[0]), np.empty(xy.shape[0])
        if self._everywhere:
            out.fill(0.0)
            within.fill(math.inf)
            return out, within
        _clearance(xy, most, self._table, self._origin[0], self._origin[1], self._cell, out,
                   within)
        if self._loose:  # its marked cells may lie far from it
            within.fill(math.inf)
        return out, within

    def distances(self, xy: np.ndarray, look: np.ndarray, which: np.ndarray | None = None,
                  filters: Sequence[pymunk.ShapeFilter] | None = None) -> np.ndarray:
        """The distance [m] from each point of ``xy`` (n, 2) [m] to the nearest fixed shape
        (pymunk's point query; negative inside one), inf where none lies within ``look``
        (n,) [m] or where ``which`` (n,) is False: pymunk is asked only about the points
        :meth:`near` cannot rule out. ``filters``: each point's mover's own shape filter: its
        nearest shape through it, if fixed, is the answer (one result instead of every shape
        within ``look``)."""
        out = np.full(xy.shape[0], math.inf)
        moving = self._moving
        near = self.near(xy, look)
        if which is not None:
            near &= which
        space = self.space
        for k in np.flatnonzero(near).tolist():
            point, reach = (float(xy[k, 0]), float(xy[k, 1])), float(look[k])
            if filters is not None:
                hit = space.point_query_nearest(point, reach, filters[k])
                if hit is None or (hit.shape is not None and hit.shape.body not in moving
                                   and not hit.shape.sensor):
                    out[k] = math.inf if hit is None else hit.distance
                    continue
            for hit in space.point_query(point, reach, _EVERY_SHAPE):
                shape = hit.shape
                if shape is not None and not shape.sensor and shape.body not in moving:
                    out[k] = min(out[k], hit.distance)
        return out

    def forget(self) -> None:
        """Fixed bodies may have moved: the next :meth:`refresh` builds the cells again."""
        self._key = self._seen = self._fixed = None

    def watching(self, space: pymunk.Space, moving: Collection[pymunk.Body],
                 version: Callable[[], int] | None = None) -> "StaticCells":
        """These cells, for another set of ``moving`` bodies in ``space``: the same Space (a
        copy of a scenario rebuilt among others: its new robots come, its old ones go, and
        the fixed world, unless its version says otherwise, is what it was), or another one
        (a run rebuilt: its fixed shapes are new, and where they lie where the old ones did,
        the cells stand). Built again only where the fixed world differs."""
        if space is not self.space:
            self.space, self._version, self._seen, self._fixed = space, version, None, None
        self._moving = moving
        self._key = None  # the shapes are compared at the next refresh
        self.refresh()
        return self

    def _fixed_shapes(self, shapes: tuple[pymunk.Shape, ...]) -> list[pymunk.Shape]:
        """Of ``shapes``, those of the fixed world: no sensor, no body of the moving ones."""
        moving = self._moving
        return [shape for shape in shapes
                if not shape.sensor and shape.body is not None and shape.body not in moving]

    def refresh(self) -> None:
        """Build the cells again if a shape came or went (or after :meth:`forget`): looked
        for only when the version changed."""
        if self._version is not None:
            version = self._version()
            if version == self._seen:
                return
            self._seen = version
        key = tuple(self.space.shapes)
        if key == self._key:
            return
        self._key = key
        fixed = self._fixed_shapes(key)
        if fixed == self._fixed:  # the shapes that moved came or went: the fixed ones stand
            return
        self._fixed = fixed
        outline = [_outline_of(shape) for shape in fixed]
        if outline == self._outline:  # other shapes where the old ones were: the cells stand
            return
        self._outline = outline
        boxes = np.array([tuple(shape.cache_bb()) for shape in fixed], dtype=float).reshape(-1, 4)
        self._everywhere = not np.isfinite(boxes).all()
        if boxes.shape[0] == 0 or self._everywhere:  # nothing fixed, or nothing to mark
            self._origin, self._cell = (0.0, 0.0), 1.0
            self._table = np.zeros((2, 2), dtype=np.int32)
            return
        left, bottom = float(boxes[:, 0].min()), float(boxes[:, 1].min())
        width = float(boxes[:, 2].max()) - left
        height = float(boxes[:, 3].max()) - bottom
        cell = max(MIN_CELL, math.sqrt(max(width * height, 1e-12) / MAX_CELLS))
        cols, rows = int(width / cell) + 1, int(height / cell) + 1
        while cols * rows > MAX_CELLS:  # long thin worlds: coarser until it fits
            cell *= 1.5
            cols, rows = int(width / cell) + 1, int(height / cell) + 1
        grid = np.zeros((rows, cols), dtype=np.int32)
        self._loose = False
        for shape, box in zip(fixed, boxes.tolist()):
            self._loose |= not _mark(grid, shape, box, left, bottom, cell)
        table = np.zeros((rows + 1, cols + 1), dtype=np.int32)
        table[1:, 1:] = grid.cumsum(axis=0).cumsum(axis=1)
        self._origin, self._cell, self._table = (left, bottom), cell, table


def _mark(grid: np.ndarray, shape: pymunk.Shape, box: list[float], left: float, bottom: float,
          cell: float) -> bool:
    """Mark the cells of ``grid`` (corner at (``left``, ``bottom``) [m], cells of ``cell``
    [m]) that ``shape`` covers: those of its bounding box ``box`` (left, bottom, right, top)
    [m] that its outline, grown by its rounding radius and OUTLINE_SLACK, meets. False if it
    marked a box more than two cells across without its outline (a kind not known here)."""
    rows, cols = grid.shape
    i0 = int(math.floor((box[0] - left) / cell))
    i1 = min(int(math.floor((box[2] - left) / cell)), cols - 1)
    j0 = int(math.floor((box[1] - bottom) / cell))
    j1 = min(int(math.floor((box[3] - bottom) / cell)), rows - 1)
    small = i1 - i0 <= 1 and j1 - j0 <= 1  # two cells across at most: its box is as good
    outline = None if small else _outline(shape)
    if outline is None:  # a small box, or a kind of shape not known here
        grid[j0:j1 + 1, i0:i1 + 1] = 1
        return small
    i, j = np.meshgrid(np.arange(i0, i1 + 1), np.arange(j0, j1 + 1))
    x, y = left + i * cell, bottom + j * cell
    with np.errstate(divide="ignore", invalid="ignore"):  # flags GEOS may leave raised
        squares = shapely.box(x, y, x + cell, y + cell)
        covered = shapely.intersects(squares, outline)
    grid[j0:j1 + 1, i0:i1 + 1] |= covered.astype(np.int32)
    return True


def _outline_of(shape: pymunk.Shape) -> tuple:
    """What ``shape`` covers, as numbers: its kind, its points in the world frame [m] and its
    rounding radius [m] (its bounding box for a kind not known here)."""
    body = shape.body
    assert body is not None
    if isinstance(shape, pymunk.Circle):
        points: tuple = (tuple(body.local_to_world(shape.offset)),)
    elif isinstance(shape, pymunk.Segment):
        points = (tuple(body.local_to_world(shape.a)), tuple(body.local_to_world(shape.b)))
    elif isinstance(shape, pymunk.Poly):
        points = tuple(tuple(body.local_to_world(v)) for v in shape.get_vertices())
    else:
        points = (tuple(shape.cache_bb()),)
    return type(shape).__name__, points, float(getattr(shape, "radius", 0.0))


def _outline(shape: pymunk.Shape) -> shapely.Geometry | None:
    """What ``shape`` covers in the world frame (rounding radius and OUTLINE_SLACK included);
    None for a kind of shape not known here (its bounding box stands for it)."""
    body = shape.body
    assert body is not None
    if isinstance(shape, pymunk.Circle):
        centre = body.local_to_world(shape.offset)
        return _grown(shapely.Point(centre.x, centre.y), shape.radius)
    if isinstance(shape, pymunk.Segment):
        a, b = body.local_to_world(shape.a), body.local_to_world(shape.b)
        return _grown(shapely.LineString([(a.x, a.y), (b.x, b.y)]), shape.radius)
    if isinstance(shape, pymunk.Poly):
        corners = [body.local_to_world(v) for v in shape.get_vertices()]
        return _grown(shapely.Polygon([(p.x, p.y) for p in corners]), shape.radius)
    return None


def _grown(geometry: shapely.Geometry, radius: float) -> shapely.Geometry:
    """``geometry`` grown by ``radius`` [m] (a shape's rounding), enough that shapely's
    polygon of the round parts holds the true ones, plus OUTLINE_SLACK."""
    return geometry.buffer(radius * _SAG + OUTLINE_SLACK, quad_segs=QUAD_SEGS)


@numba.njit(cache=True)
def _clearance(xy: np.ndarray, most: np.ndarray, table: np.ndarray, left: float,
               bottom: float, cell: float, out: np.ndarray, within: np.ndarray) -> None:
    """``out[k]``: the half-width m * ``cell`` of the largest square block of cells about
    ``xy[k]``'s cell with no marked cell (a shape outside the block is farther than that from
    any point inside its middle cell), less SLACK, at most ``most[k]`` [m]; 0 for a point that
    is not finite. ``within[k]``: how far a corner of the smallest block with a marked cell
    is, grown by a cell (a shape covers part of that cell, or of one next to it), plus SLACK
    and OUTLINE_SLACK; inf where no block up to ``most[k]`` holds one. ``table``: the cells' summed-area table (see
    :func:`_near_cells`)."""
    rows, cols = table.shape[0] - 1, table.shape[1] - 1
    for k in range(xy.shape[0]):
        x, y = xy[k, 0], xy[k, 1]
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(most[k])):
            out[k] = 0.0
            within[k] = math.inf
            continue
        ci = math.floor((x - left) / cell)
        cj = math.floor((y - bottom) / cell)
        lo, hi = -1, int(most[k] / cell) + 1  # empty up to lo cells, not at hi (or beyond most)
        while hi - lo > 1:
            m = (lo + hi) // 2
            i0, i1 = min(max(ci - m, 0), cols), min(max(ci + m + 1, 0), cols)
            j0, j1 = min(max(cj - m, 0), rows), min(max(cj + m + 1, 0), rows)
            if table[j1, i1] - table[j0, i1] - table[j1, i0] + table[j0, i0] > 0:
                hi = m
            else:
                lo = m
        out[k] = min(max(lo * cell - SLACK, 0.0), most[k])
        top = int(most[k] / cell) + 1
        # A marked cell is met by its shape's outline, or lies in the box (two cells across at
        # most) of a shape marked by its box: the shape is within the block one cell wider.
        within[k] = (math.sqrt(2.0) * (hi + 2) * cell + SLACK + OUTLINE_SLACK if hi < top
                     else math.inf)


@numba.njit(cache=True)
def _near_cells(xy: np.ndarray, look: np.ndarray, table: np.ndarray, left: float,
                bottom: float, cell: float, near: np.ndarray) -> None:
    """``near[k]``: whether a marked cell lies in the square of half-width ``look[k]`` [m]
    (plus SLACK) about ``xy[k]`` [m]; True for a point that is not finite. ``table``: the cells' summed-area table, the grid's corner at
    (``left``, ``bottom``) [m], cells of ``cell`` [m]."""
    rows, cols = table.shape[0] - 1, table.shape[1] - 1
    for k in range(xy.shape[0]):
        x, y, r = xy[k, 0], xy[k, 1], look[k] + SLACK
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(r)):
            near[k] = True
            continue
        # Cells i0 .. i1 - 1 and j0 .. j1 - 1 (the table's indices), clipped to the grid.
        i0 = min(max(math.floor((x - r - left) / cell), 0), cols)
        i1 = min(max(math.floor((x + r - left) / cell) + 1, 0), cols)
        j0 = min(max(math.floor((y - r - bottom) / cell), 0), rows)
        j1 = min(max(math.floor((y + r - bottom) / cell) + 1, 0), rows)
        near[k] = table[j1, i1] - table[j0, i1] - table[j1, i0] + table[j0, i0] > 0

