"""Static pymunk geometry from a map: convex polygons plus segment chains, in world metres.

From an occupancy grid (``geometry_from_grid``): a cell is *solid* when it is occupied (at least
``occupied_thresh``) or unknown. Unknown counts as solid on purpose: a SLAM map is unknown
outside its walls and wherever the sensor never looked, and a robot must not drive off into
what nobody has seen. Everything outside the grid is solid too, so the geometry is closed.

The outlines between solid and free cells are the staircase ``pymunk.autogeometry.march_hard``
traces along the cell edges (computed with numpy, see ``trace_outlines``), simplified with
``autogeometry.simplify_curves`` within half a cell. A solid island winds counter-clockwise and
the rim of a free region clockwise. An island with no free region inside becomes convex pieces
(``autogeometry.convex_decomposition``); every other outline (room walls, islands that enclose
free space) becomes a chain of segments, so no piece ever fills a room.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import pymunk
import shapely
from pymunk import autogeometry

from pymunk_bot.geometry.plane import polygons, signed_area
from pymunk_bot.maps.grid import OCCUPIED_THRESH, OccupancyGrid

MAX_DECOMPOSE_VERTICES = 2000  # larger islands stay segment chains (decomposition is quadratic)
PINHOLE_CELLS = 4.0  # [cells] enclosed free pockets up to this area become solid
DECOMPOSE_TOLERANCE = 1.0  # [cells] concavity depth an island's convex pieces may fill


@dataclass(frozen=True)
class FilledArea:
    """A painted area of a vector map: closed outlines (n, 2) [m] and SVG's fill rule."""

    outlines: tuple[np.ndarray, ...]
    nonzero: bool = True  # False: even-odd

    def contains(self, x: float, y: float) -> bool:
        """Whether the point (x, y) [m] is painted. Counted here, not by GEOS: GEOS has no
        nonzero fill rule (it needs valid polygons, where SVG paints any outlines)."""
        winding = 0
        crossings = 0
        for outline in self.outlines:
            a, b = outline, np.roll(outline, -1, axis=0)
            up = (a[:, 1] <= y) & (b[:, 1] > y)
            down = (a[:, 1] > y) & (b[:, 1] <= y)
            side = (b[:, 0] - a[:, 0]) * (y - a[:, 1]) - (x - a[:, 0]) * (b[:, 1] - a[:, 1])
            winding += int(np.count_nonzero(up & (side > 0)) - np.count_nonzero(down & (side < 0)))
            crossings += int(np.count_nonzero((up & (side > 0)) | (down & (side < 0))))
        return winding != 0 if self.nonzero else crossings % 2 == 1


@dataclass(frozen=True)
class MapGeometry:
    """Static obstacles of a map, ready for pymunk (all in world metres).

    ``polygons``: convex pieces, counter-clockwise, each (n, 2). ``segments``: (m, 4) rows of
    x0, y0, x1, y1 with ``segment_radius`` (m,). ``extent``: (x0, y0, x1, y1), the map's area;
    nothing can pass its edge. ``solid``: for a grid map, the (rows, cols) mask of solid cells
    of ``grid``. ``filled``: for vector maps, the painted areas.
    """

    polygons: tuple[np.ndarray, ...]
    segments: np.ndarray
    segment_radius: np.ndarray
    extent: tuple[float, float, float, float]
    grid: OccupancyGrid | None = None
    solid: np.ndarray | None = None
    filled: tuple[FilledArea, ...] = field(default=())

    @property
    def size(self) -> tuple[float, float]:
        """Width and height of the extent [m]."""
        x0, y0, x1, y1 = self.extent
        return (x1 - x0, y1 - y0)

    def is_solid(self, x: float, y: float) -> bool:
        """Whether the point (x, y) [m] lies in the map's solid (a solid cell of a grid map,
        unknown ones included; a painted area of a vector map) or outside its extent. The
        physics holds only the solid's outline: a point deep inside it touches no shape."""
        x0, y0, x1, y1 = self.extent
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            return True
        if self.grid is not None and self.solid is not None:
            row, col = self.grid.cell_of(np.array([x, y]))
            if not self.grid.inside(row, col):
                return True
            return bool(self.solid[int(row), int(col)])
        return any(area.contains(x, y) for area in self.filled)

    def random_free_point(self, rng: np.random.Generator) -> tuple[float, float] | None:
        """A point [m] drawn uniformly from a grid map's free cells (never an occupied or
        unknown one); None for a vector map or a grid with no free cell. A map's free space can
        be a few percent of its extent (TurtleBot3's world: 2 %), where drawing in the extent
        and rejecting would mostly miss."""
        if self.grid is None or self.solid is None:
            return None
        cells = self._free_cells
        if cells.size == 0:
            return None
        row, col = divmod(int(cells[rng.integers(cells.size)]), self.solid.shape[1])
        r = self.grid.resolution
        return (float(self.grid.origin[0] + (col + rng.random()) * r),
                float(self.grid.origin[1] + (row + rng.random()) * r))

    @cached_property
    def _free_cells(self) -> np.ndarray:
        """Flat indices (row-major) of the grid's cells that are not solid."""
        assert self.solid is not None
        return np.flatnonzero(~self.solid)

    @property
    def shape_count(self) -> int:
        """Number of pymunk shapes the geometry makes (pieces plus segments)."""
        return len(self.polygons) + len(self.segments)

    @cached_property
    def shapes(self) -> np.ndarray:
        """The pieces, then the segments (as lines, without their radius), as shapely
        geometries: the order of ``polygons`` then ``segments``."""
        lines = shapely.linestrings(self.segments.reshape(-1, 2, 2))
        return np.concatenate([polygons(self.polygons), np.asarray(lines, dtype=object)])

    @cached_property
    def shape_index(self) -> shapely.STRtree:
        """An R-tree over :attr:`shapes`, for what lies near a point."""
        return shapely.STRtree(self.shapes)


def solid_cells(grid: OccupancyGrid, occupied_thresh: float = OCCUPIED_THRESH,
                unknown_is_solid: bool = True) -> np.ndarray:
    """Boolean (rows, cols): occupied cells, plus unknown ones when ``unknown_is_solid``."""
    solid = grid.occupied(occupied_thresh)
    return solid | grid.unknown() if unknown_is_solid else solid


def geometry_from_grid(grid: OccupancyGrid, occupied_thresh: float = OCCUPIED_THRESH,
                       unknown_is_solid: bool = True) -> MapGeometry:
    """Trace the solid cells of ``grid`` into convex pieces and segment chains (see module doc)."""
    solid = solid_cells(grid, occupied_thresh, unknown_is_solid)
    padded = np.pad(solid, 1, constant_values=True)  # outside the map is solid: outlines close
    loops = [_simplify(straighten(loop)) for loop in trace_outlines(padded)]
    loops = [loop for loop in loops if len(loop) >= 4]  # closed: first point repeated
    areas = np.array([signed_area(loop) for loop in loops])
    islands = [i for i in range(len(loops)) if areas[i] > 0]
    # Pinholes (free pockets of a few cells inside solid, e.g. where rasterised boxes overlap)
    # are filled: no robot fits, no ray gets in, and kept they would turn their whole island
    # into segment chains.
    rims = [i for i in range(len(loops)) if areas[i] < -PINHOLE_CELLS]
    enclosing = _islands_enclosing(loops, islands, rims)
    polygons: list[np.ndarray] = []
    chains: list[np.ndarray] = []
    for i in islands:
        # Concavities up to a cell deep are filled: where rasterised boxes meet, the notches
        # between them would otherwise each cost a piece (and LiDAR time).
        pieces = None if i in enclosing else convex_pieces(loops[i], DECOMPOSE_TOLERANCE)
        if pieces is None:
            chains.append(loops[i])
        else:
            polygons += pieces
    chains += [loops[i] for i in rims]
    # Padded sample s sits at the centre of grid cell s - 1: world = origin + (s - 0.5) * res.
    res = grid.resolution
    offset = np.array(grid.origin) - 0.5 * res
    polygons = [offset + p * res for p in polygons]
    segments = np.concatenate([edge_chain(c) for c in chains]) if chains else np.empty((0, 4))
    segments = segments * res + np.tile(offset, 2)
    x0, y0 = grid.origin
    width, height = grid.size
    return MapGeometry(tuple(polygons), segments, np.zeros(len(segments)),
                       (x0, y0, x0 + width, y0 + height), grid, solid)


def trace_outlines(solid: np.ndarray) -> list[np.ndarray]:
    """Closed outlines of the solid cells of a mask whose border cells are all solid.

    The same staircase ``autogeometry.march_hard`` traces with samples at the cell centres
    (x = column, y = row, outlines on the half-integer cell edges, solid on the left: islands
    counter-clockwise), with straight runs merged. It is traced with numpy because march_hard
    calls back into Python once per sample (about 1 us: 16 s for a 4000 x 4000 map) and GEOS
    has no raster tracing (a shapely union of the map's 136,000 row runs of solid cells takes
    3.3 s against 0.2 s here, and joins corner-touching cells its own way). Cells
    touching only at a corner are joined (solid is 8-connected), so a diagonal wall stays one
    outline with no gap at its corners. Returns (n, 2) loops whose last point repeats the first.
    """
    runs = [_runs(solid, vertical=True), _runs(solid, vertical=False)]
    start = np.concatenate([r[0] for r in runs])  # doubled coordinates: integers
    end = np.concatenate([r[1] for r in runs])
    if not len(start):
        return []
    heading = np.sign(end - start)
    width = int(max(start[:, 0].max(), end[:, 0].max())) + 2
    start_key = (start[:, 1] * width + start[:, 0]).tolist()
    end_key = (end[:, 1] * width + end[:, 0]).tolist()
    heading_list = heading.tolist()
    outgoing: dict[int, list[int]] = {}
    for i, key in enumerate(start_key):
        outgoing.setdefault(key, []).append(i)
    used = bytearray(len(start_key))
    loops = []
    for first in range(len(start_key)):
        if used[first]:
            continue
        chain = [first]
        used[first] = 1
        i = first
        while end_key[i] != start_key[first]:
            options = [j for j in outgoing[end_key[i]] if not used[j]]
            if len(options) > 1:  # a corner two solid cells share: turn right, keep them joined
                hx, hy = heading_list[i]
                right = [hy, -hx]
                options = [j for j in options if heading_list[j] == right] or options
            i = options[0]
            used[i] = 1
            chain.append(i)
        points = start[chain]
        loops.append(np.vstack([points, points[:1]]) / 2.0)
    return loops


def _runs(solid: np.ndarray, vertical: bool) -> tuple[np.ndarray, np.ndarray]:
    """Straight runs of cell edges between solid and free cells, solid on the left, as
    (start, end) points in doubled sample coordinates (so cell edges are integers)."""
    grid = solid if vertical else solid.T  # transposed: rows become columns
    differs = grid[:, :-1] != grid[:, 1:]
    along, across = np.nonzero(differs.T)  # sorted by edge line, then along it
    if not len(along):  # all solid or all free: no edge between them
        return np.empty((0, 2), dtype=np.int64), np.empty((0, 2), dtype=np.int64)
    solid_low = grid[across, along]  # solid on the lower-index side of the edge
    # A run continues while the line and the side stay the same and the edges are adjacent.
    breaks = np.ones(len(along), dtype=bool)
    breaks[1:] = (np.diff(along) != 0) | (np.diff(across) != 1) | (solid_low[1:] != solid_low[:-1])
    first = np.flatnonzero(breaks)
    last = np.append(first[1:], len(along)) - 1
    line = 2 * along[first] + 1
    lo, hi = 2 * across[first] - 1, 2 * across[last] + 1
    low_solid = solid_low[first]
    # Vertical edges: solid to the west goes up (+y). Transposed (horizontal edges), the
    # lower side is south, and solid to the south goes west (-x): the opposite order.
    forward = low_solid if vertical else ~low_solid
    a = np.where(forward, lo, hi)
    b = np.where(forward, hi, lo)
    if vertical:
        return np.stack([line, a], axis=1), np.stack([line, b], axis=1)
    return np.stack([a, line], axis=1), np.stack([b, line], axis=1)


def straighten(loop: np.ndarray) -> np.ndarray:
    """A staircase loop (cell edges) as the points a half-cell Douglas-Peucker can straighten.

    A staircase zigzags half a cell either side of the line it stands for, too far for a
    half-cell tolerance. Along a staircase the turns alternate left and right and every step
    has a one-cell edge; at a real corner two turns in a row go the same way, or both edges
    are longer. So every edge's midpoint is kept, and a vertex only where it is a real corner:
    a rotated box's stairs become the lines through their edges' midpoints (within half a cell
    of the cells) and its corners stay. Both sides of a one-cell diagonal wall stay apart (half
    a cell either side of its centre line).
    """
    points = loop[:-1]
    if len(points) < 4:
        return loop
    incoming = points - np.roll(points, 1, axis=0)  # edge ending at each vertex
    outgoing = np.roll(incoming, -1, axis=0)
    turn = np.sign(incoming[:, 0] * outgoing[:, 1] - incoming[:, 1] * outgoing[:, 0])
    step = np.minimum(np.abs(incoming).sum(axis=1), np.abs(outgoing).sum(axis=1)) <= 1.0 + 1e-9
    corner = (turn == np.roll(turn, 1)) | (turn == np.roll(turn, -1)) | ~step
    midpoints = points + 0.5 * outgoing  # of the edge starting at each vertex
    both = np.stack([points, midpoints], axis=1).reshape(-1, 2)
    keep = np.stack([corner, np.ones(len(points), dtype=bool)], axis=1).reshape(-1)
    out = both[keep]
    return np.vstack([out, out[:1]])


def _simplify(loop: np.ndarray) -> np.ndarray:
    """Douglas-Peucker within half a sample; the loop stays closed."""
    simple = autogeometry.simplify_curves([tuple(p) for p in loop], 0.5)
    out = np.array([(v.x, v.y) for v in simple])
    if len(out) and not np.array_equal(out[0], out[-1]):
        out = np.vstack([out, out[:1]])
    return out


def edge_chain(points: np.ndarray) -> np.ndarray:
    """(n - 1, 4) segments x0, y0, x1, y1 joining consecutive points (n, 2)."""
    return np.hstack([points[:-1], points[1:]])


def _islands_enclosing(loops: list[np.ndarray], islands: list[int], rims: list[int]) -> set[int]:
    """Islands that have a free region (a rim loop) inside them: filling them would fill it.
    A rim lies inside an island when its first point does (on the outline counts: kept as
    segments, an island never fills a room)."""
    if not islands or not rims:
        return set()
    rim_points = shapely.points(np.array([loops[i][0] for i in rims]))
    shapes = polygons([loops[i] for i in islands])
    found, _ = shapely.STRtree(rim_points).query(shapes, predicate="intersects")
    return {islands[k] for k in np.unique(found).tolist()}


def convex_pieces(loop: np.ndarray, tolerance: float = 0.01) -> list[np.ndarray] | None:
    """Convex pieces of a closed counter-clockwise loop, or None to keep it as segments; a loop
    with every vertex within ``tolerance`` of its convex hull's outline is one piece."""
    if len(loop) > MAX_DECOMPOSE_VERTICES:
        return None
    points = [tuple(p) for p in loop]
    if not autogeometry.is_closed(points) or autogeometry.area_for_poly(points) <= 0:
        return None
    hull = autogeometry.to_convex_hull(points, 0.0)
    outline = shapely.linestrings([(v.x, v.y) for v in hull])
    gap = shapely.distance(outline, shapely.points(loop[:-1]))
    if gap.max() <= tolerance:  # convex within the tolerance (a box, a pillar): one piece
        hulls = [hull]
    else:
        hulls = autogeometry.convex_decomposition(points, tolerance)
    pieces = []
    for hull in hulls:
        piece = np.array([(v.x, v.y) for v in hull])
        if len(piece) > 1 and np.array_equal(piece[0], piece[-1]):
            piece = piece[:-1]
        if len(piece) >= 3 and autogeometry.area_for_poly([tuple(p) for p in piece]) > 1e-9:
            pieces.append(piece)
    return pieces or None


def add_to_space(space: pymunk.Space, geometry: MapGeometry, friction: float = 0.5,
                 collision_type: int = 0) -> list[pymunk.Shape]:
    """Add the map's shapes to ``space`` on its static body; returns them in the order added."""
    body = space.static_body
    shapes: list[pymunk.Shape] = []
    for piece in geometry.polygons:
        shapes.append(pymunk.Poly(body, [tuple(p) for p in piece], radius=0.0))
    for (x0, y0, x1, y1), radius in zip(geometry.segments.tolist(),
                                        geometry.segment_radius.tolist()):
        shapes.append(pymunk.Segment(body, (x0, y0), (x1, y1), radius))
    for shape in shapes:
        shape.friction = friction
        shape.collision_type = collision_type
    space.add(*(shapes[i] for i in interleaved(len(shapes))))
    return shapes


def interleaved(n: int) -> np.ndarray:
    """0..n-1 in a fixed, well-spread order (the golden-ratio sequence). Chipmunk's static index
    grows lopsided when neighbouring shapes arrive in order along a wall: 40,000 segments of one
    traced outline took 4.7 s to add in order, 0.3 s interleaved (190,000: 2.2 s, not minutes)."""
    return np.argsort((np.arange(n) * 0.6180339887498949) % 1.0, kind="stable")


def free_disc(geometry: MapGeometry, x: float, y: float, radius: float) -> bool:
    """True when a disc of ``radius`` [m] at (x, y) [m] lies inside the map's extent and
    touches no solid cell, no filled area and no shape of the geometry (a point on a piece's
    outline is inside it; a disc may graze a piece or segment)."""
    x0, y0, x1, y1 = geometry.extent
    if not (x0 + radius <= x <= x1 - radius and y0 + radius <= y <= y1 - radius):
        return False
    if geometry.grid is not None and geometry.solid is not None \
            and _touches_solid_cell(geometry.grid, geometry.solid, x, y, radius):
        return False
    if geometry.shape_count:
        centre = shapely.Point(x, y)
        widest = float(geometry.segment_radius.max()) if len(geometry.segment_radius) else 0.0
        near = geometry.shape_index.query(centre, predicate="dwithin", distance=radius + widest)
        if len(near):
            gap = shapely.distance(geometry.shapes[near], centre)
            pieces = len(geometry.polygons)
            reach = radius + np.concatenate((np.zeros(pieces), geometry.segment_radius))[near]
            if ((gap < reach) | ((near < pieces) & (gap == 0.0))).any():
                return False
    return not any(area.contains(x, y) for area in geometry.filled)


def _touches_solid_cell(grid: OccupancyGrid, solid: np.ndarray, x: float, y: float,
                        radius: float) -> bool:
    res = grid.resolution
    ox, oy = grid.origin
    c0 = max(0, int(np.floor((x - radius - ox) / res)))
    c1 = min(grid.cols, int(np.floor((x + radius - ox) / res)) + 1)
    r0 = max(0, int(np.floor((y - radius - oy) / res)))
    r1 = min(grid.rows, int(np.floor((y + radius - oy) / res)) + 1)
    window = solid[r0:r1, c0:c1]
    if not window.any():
        return False
    cx = ox + (np.arange(c0, c1) + 0.5) * res
    cy = oy + (np.arange(r0, r1) + 0.5) * res
    dx = np.maximum(np.abs(cx - x) - 0.5 * res, 0.0)  # distance to each cell's square
    dy = np.maximum(np.abs(cy - y) - 0.5 * res, 0.0)
    return bool((window & (np.add.outer(dy * dy, dx * dx) < radius * radius)).any())
