"""Batch ray casting that returns what pymunk's ``Space.segment_query_first`` returns.

How it stays exact: every (primitive, ray) test repeats Chipmunk's own floating-point
expressions in Chipmunk's order (cpPolyShapeSegmentQuery, CircleSegmentQuery,
cpSegmentShapeSegmentQuery) on world geometry built with Chipmunk's transform arithmetic,
so each candidate alpha is bit-identical to pymunk's, and the answer per ray is their
minimum, as in cpSpaceSegmentQueryFirst. The start-inside rule (alpha 0 when the point
query at the origin gives distance <= 0) is asked of pymunk itself. pymunk also skips a
static shape whose bounding box a rounded slab test says the segment misses; that can
differ from the shape test only for rays running (within rounding) along a box side or
through a box corner lying on the shape, so such rays are detected with wide margins and
answered by pymunk directly. Everything else only chooses which pairs to test, always
with margins far above rounding, so the choice never changes a result.

How it is fast: shapes the filter rejects are dropped, back-facing polygon edges are
dropped by Chipmunk's own plane test, and each primitive meets only the rays inside the
angle it subtends (the rays are sorted by angle, so that is an index range). Dense scenes
are traced in rings of growing distance, so rays already stopped nearby skip far shapes.
Static geometry is cached in world coordinates; moving bodies are re-read every cast.

Differences from pymunk, by design:
- pymunk queries see a shape where it was at the last ``space.step()`` or reindex; this
  caster uses each body's current transform. They agree whenever a body moved by hand
  has been reindexed (``space.reindex_shapes_for_body``), and always after a step.
- Changing a shape's filter, radius or vertices, or a body's type, without adding or
  removing a shape is not detected: call :meth:`RayCaster.invalidate`.
- Bodies put to sleep (only if the space enables sleeping) are treated as moving bodies,
  so rays grazing their bounding boxes are not handed to pymunk (a measure-zero case).
"""

from __future__ import annotations

import bisect
import itertools
import math
import sys

import numpy as np
import pymunk

__all__ = ["RayCaster", "reference_cast"]

_TWO_PI = 2.0 * math.pi
# Chipmunk skips a polygon plane when |a.n - b.n| is below this literal (written 10e-6 in C).
_PARALLEL_EPS = 10e-6
# cpvnormalize adds CPFLOAT_MIN (DBL_MIN) to the length; kept for bit-equal normals.
_DBL_MIN = sys.float_info.min
# Candidate rays of a sharp polygon edge: its end points' directions widened by this margin
# [rad], or every ray when the origin is within _EDGE_NEAR * scale of the edge's plane.
_EDGE_MARGIN = 1e-7
_EDGE_NEAR = 1e-5
# Rays within this angle [rad] of a box side line through the origin are left to pymunk.
_SIDE_ANGLE = 1e-4
# Above this many shapes in range, trace in rings of growing distance (occlusion culling):
# about _RING_SHAPES shapes in the first ring, each next ring _RING_GROWTH times farther.
_DENSE_SHAPES = 160
_RING_SHAPES = 48
_RING_GROWTH = 3.0
_MAX_RINGS = 3


def _check_args(origin: tuple[float, float], angles: np.ndarray,
                max_range: float) -> tuple[float, float, np.ndarray, float]:
    """Validated (ox, oy, angles as float64, max_range)."""
    ox, oy = float(origin[0]), float(origin[1])
    ang = np.asarray(angles, dtype=np.float64)
    if ang.ndim != 1:
        raise ValueError(f"angles must be a 1-D array, got shape {ang.shape}")
    rng = float(max_range)
    if not (math.isfinite(rng) and rng > 0.0):
        raise ValueError(f"max_range must be positive and finite, got {max_range!r}")
    if not (math.isfinite(ox) and math.isfinite(oy)) or not bool(np.isfinite(ang).all()):
        raise ValueError("origin and angles must be finite")
    return ox, oy, ang, rng


def _endpoints(ox: float, oy: float, ang: np.ndarray,
               rng: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """cos, sin and the (2, n) segment end points origin + rng * (cos, sin); shared so both
    casters query identical segments."""
    cos, sin = np.cos(ang), np.sin(ang)
    ends = np.empty((2, ang.shape[0]))
    np.multiply(rng, cos, out=ends[0])
    np.multiply(rng, sin, out=ends[1])
    ends[0] += ox
    ends[1] += oy
    return cos, sin, ends


def reference_cast(space: pymunk.Space, origin: tuple[float, float], angles: np.ndarray,
                   max_range: float,
                   shape_filter: pymunk.ShapeFilter = pymunk.ShapeFilter()) -> np.ndarray:
    """The ground truth: one ``segment_query_first`` per ray; ``alpha * max_range`` or ``max_range``."""
    ox, oy, ang, rng = _check_args(origin, angles, max_range)
    _, _, ends = _endpoints(ox, oy, ang, rng)
    out = np.full(ang.shape[0], rng)
    query, start = space.segment_query_first, (ox, oy)
    for i, end in enumerate(zip(*ends.tolist())):
        hit = query(start, end, 0.0, shape_filter)
        if hit is not None:
            out[i] = hit.alpha * rng
    return out


# ----------------------------------------------------------------------------------------
# Public caster
# ----------------------------------------------------------------------------------------

class RayCaster:
    """Casts batches of rays against every shape in a pymunk Space."""

    def __init__(self, space: pymunk.Space) -> None:
        self.space = space
        self._cache = _SceneCache(space)

    def invalidate(self) -> None:
        """Drop cached geometry; needed only after changing a shape's filter, size or vertices,
        or a body's type, without adding or removing a shape."""
        self._cache.invalidate()

    def cast(self, origin: tuple[float, float], angles: np.ndarray, max_range: float,
             shape_filter: pymunk.ShapeFilter = pymunk.ShapeFilter()) -> np.ndarray:
        """Distance along each ray (world-frame angles [rad]) from origin to the first shape the
        filter admits; max_range where nothing is hit within max_range. float64 array, len(angles)."""
        ox, oy, ang, rng = _check_args(origin, angles, max_range)
        n_rays = ang.shape[0]
        if n_rays == 0:
            return np.empty(0)
        cos, sin, ends = _endpoints(ox, oy, ang, rng)
        parts, bound = self._cache.world()
        # Coordinate scale of this cast: rounding errors are ~1e-16 of it.
        scale = 1.0 + abs(ox) + abs(oy) + rng
        slack = 1e-9 * scale
        keep, n_keep = self._cache.admitted(shape_filter)
        dense = n_keep > _DENSE_SHAPES
        if dense:  # cull by distance; in small worlds the pair tests reject far shapes anyway
            dx, dy = bound[0] - ox, bound[1] - oy
            dist = np.sqrt(dx * dx + dy * dy)
            gap = dist - bound[2]  # lower bound on the distance to any point of the shape
            keep = keep & (gap <= rng + slack)
            n_keep = int(np.count_nonzero(keep))
            rings = (gap, dx, dy, dist)
        if n_keep == 0:
            return np.full(n_rays, rng)
        # cpShapeSegmentQuery reports alpha 0 when its point query at the start gives a
        # distance <= 0; the nearest-shape query runs that same test on the same shapes.
        inside = self.space.point_query_nearest((ox, oy), slack, shape_filter)
        if inside is not None and inside.distance <= 0.0:
            bb = inside.shape.bb
            if bb.left <= ox <= bb.right and bb.bottom <= oy <= bb.top:
                return np.zeros(n_rays)  # every ray's bounding-box test admits the shape
            # Distance 0 by underflow just outside the box: pymunk's box test decides ray by ray.
            return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        best = np.ones(n_rays)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            fan = _Fan(np.arctan2(sin, cos), ends)
            self._side_flags(fan, ox, oy, scale)
            if n_keep <= _DENSE_SHAPES:
                _Scene(parts, keep, ox, oy, scale, rng, subset=dense).trace(fan, fan.every, best)
            else:
                _trace_rings(parts, bound, keep, n_keep, rings, fan, best, (ox, oy, rng, scale))
        if fan.flagged:
            # Rays near a box corner or along a box side (see _corner_flags): ask pymunk.
            query, start = self.space.segment_query_first, (ox, oy)
            for i in np.unique(np.concatenate(fan.flagged)).tolist():
                hit = query(start, (ends[0, i], ends[1, i]), 0.0, shape_filter)
                best[i] = 1.0 if hit is None else hit.alpha
        return best * rng

    def _side_flags(self, fan: _Fan, ox: float, oy: float, scale: float) -> None:
        """Flag the rays that may run along a side line of a static bounding box.

        Such a ray starts (within rounding) on the line and points along it; pymunk's box
        test is then decided by rounding (see _corner_flags). The tolerances are generous
        because flagged rays are exact anyway, only slower."""
        near, corner = 1e-7 * scale, _EDGE_NEAR * scale
        directions, close = [], 0
        for sides, v, along in ((self._cache.side_x, ox, (-0.5 * math.pi, 0.5 * math.pi)),
                                (self._cache.side_y, oy, (-math.pi, 0.0, math.pi))):
            i = bisect.bisect_left(sides, v - corner)
            if i < len(sides) and sides[i] <= v + corner:
                close += 1
                i = bisect.bisect_left(sides, v - near)
                if i < len(sides) and sides[i] <= v + near:
                    directions.extend(along)
        if close == 2:
            # Within _EDGE_NEAR * scale of both a vertical and a horizontal side line, so
            # perhaps of a flag, whose direction is then too uncertain: flag every ray.
            fan.flagged.append(np.arange(fan.ends.shape[1]))
        elif directions:
            a = np.array(directions)
            first, counts = fan.every.ranges(a - _SIDE_ANGLE, a + _SIDE_ANGLE, np.zeros(a.size, dtype=bool))
            fan.flagged.append(fan.every.expand(first, counts)[0])


# ----------------------------------------------------------------------------------------
# Geometry cache
# ----------------------------------------------------------------------------------------

# Rows of a primitive table (one column per primitive). Every primitive is a capsule A-B
# of radius RAD; the kinds are stored contiguously in this order:
#   edge:    A = vertex i, B = vertex i-1, N = plane normal, VN = A.N, RAD = poly radius,
#            DTMIN = cross(N, B), DTMAX = cross(N, A)       (cpPolyShapeSegmentQuery terms)
#   flag:    A = B = a corner of a static shape's bounding box that lies on the shape (see
#            _corner_flags); rays through it are handed to pymunk itself
#   circle:  A = B = centre (also the rounded corners of polys with a radius)
#   segment: A, B = end points, N = the segment's normal
AX, AY, BX, BY, RAD, VN, NX, NY, DTMIN, DTMAX = range(10)
_RAW = [AX, AY, BX, BY, RAD, NX, NY]  # the rows _Collector fills
_ROWS = 10
_KINDS = 4


def _body_transform(body: pymunk.Body) -> tuple[float, float, float, float]:
    """(cos, sin, tx, ty) of the body's cpTransform, read exactly.

    cpBodyGetRotation returns the transform's (a, b) and cpBodyGetPosition its (tx, ty)
    (c = -b, d = a); the public properties return the same numbers at ~3x the cost."""
    rot = pymunk.cp.cpBodyGetRotation(body._body)
    pos = pymunk.cp.cpBodyGetPosition(body._body)
    return rot.x, rot.y, pos.x, pos.y


def _transforms(handles: list) -> np.ndarray:
    """(4, n) cos, sin, tx, ty of many bodies (their cffi handles), as _body_transform."""
    rotation, position = pymunk.cp.cpBodyGetRotation, pymunk.cp.cpBodyGetPosition
    out: list[float] = []
    add = out.extend
    for h in handles:
        r, p = rotation(h), position(h)
        add((r.x, r.y, p.x, p.y))
    return np.array(out).reshape(-1, 4).T


def _moved(rows: np.ndarray, bound: np.ndarray, tf: np.ndarray, prim_body: np.ndarray,
           shape_body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local tables to world: cpTransformPoint / cpTransformVect in Chipmunk's operation order,
    then the derived edge terms."""
    rx, ry, tx, ty = tf.take(prim_body, axis=1)
    out = np.empty_like(rows)
    for x, y in ((AX, AY), (BX, BY)):
        out[x] = rx * rows[x] - ry * rows[y] + tx
        out[y] = ry * rows[x] + rx * rows[y] + ty
    out[NX] = rx * rows[NX] - ry * rows[NY]
    out[NY] = ry * rows[NX] + rx * rows[NY]
    out[RAD] = rows[RAD]
    out[VN] = out[AX] * out[NX] + out[AY] * out[NY]
    out[DTMIN] = out[NX] * out[BY] - out[NY] * out[BX]
    out[DTMAX] = out[NX] * out[AY] - out[NY] * out[AX]
    rx, ry, tx, ty = tf.take(shape_body, axis=1)
    world_bound = np.stack((rx * bound[0] - ry * bound[1] + tx, ry * bound[0] + rx * bound[1] + ty, bound[2]))
    return out, world_bound


class _Collector:
    """Body-local primitives of a list of shapes, grouped by kind (no flags)."""

    def __init__(self) -> None:
        self.kinds: tuple[list[list[float]], ...] = ([], [], [], [])
        self.owners: tuple[list[int], ...] = ([], [], [], [])
        self.bound: list[list[float]] = []  # bounding circle per shape: cx, cy, radius

    def add(self, shape: pymunk.Shape, index: int) -> None:
        edges, _, circles, segments = self.kinds
        if isinstance(shape, pymunk.Poly):
            verts = [tuple(v) for v in shape.get_vertices()]
            r = shape.radius
            for (qx, qy), (px, py) in zip(verts, verts[-1:] + verts[:-1]):
                # SetVerts: n = cpvnormalize(cpvrperp(v_i - v_{i-1})), rperp(x, y) = (y, -x).
                ex, ey = qx - px, qy - py
                inv = 1.0 / (math.sqrt(ey * ey + (-ex) * (-ex)) + _DBL_MIN)
                edges.append([qx, qy, px, py, r, ey * inv, (-ex) * inv])
                self.owners[0].append(index)
            if r > 0.0:  # rounded corners: CircleSegmentQuery at each vertex
                circles.extend([[x, y, x, y, r, 0.0, 0.0] for x, y in verts])
                self.owners[2].extend([index] * len(verts))
            cx = sum(v[0] for v in verts) / len(verts)
            cy = sum(v[1] for v in verts) / len(verts)
            self.bound.append([cx, cy, max(math.hypot(x - cx, y - cy) for x, y in verts) + r])
        elif isinstance(shape, pymunk.Circle):
            (cx, cy), r = shape.offset, shape.radius
            circles.append([cx, cy, cx, cy, r, 0.0, 0.0])
            self.owners[2].append(index)
            self.bound.append([cx, cy, r])
        elif isinstance(shape, pymunk.Segment):
            (ax, ay), (bx, by), (nx, ny), r = shape.a, shape.b, shape.normal, shape.radius
            segments.append([ax, ay, bx, by, r, nx, ny])
            self.owners[3].append(index)
            self.bound.append([(ax + bx) / 2, (ay + by) / 2, math.hypot(bx - ax, by - ay) / 2 + r])
        else:
            raise TypeError(f"unsupported shape type {type(shape).__name__}")

    def tables(self) -> tuple[np.ndarray, np.ndarray, tuple[int, ...], np.ndarray]:
        """(rows, owner shape per column, per-kind counts, bounding circles)."""
        rows = np.zeros((_ROWS, sum(len(k) for k in self.kinds)))
        raw = [r for kind in self.kinds for r in kind]
        if raw:
            rows[_RAW] = np.array(raw, dtype=np.float64).T
        owner = np.array([i for kind in self.owners for i in kind], dtype=np.intp)
        counts = tuple(len(k) for k in self.kinds)
        bound = np.array(self.bound, dtype=np.float64).reshape(-1, 3).T.copy()
        return rows, owner, counts, bound


class _World:
    """A primitive table: rows (see AX...), owner shape of each column, column count of each
    kind, and each shape's bounding circle (cx, cy, radius)."""

    def __init__(self, rows: np.ndarray, owner: np.ndarray, counts: tuple[int, ...],
                 bound: np.ndarray, rounded: bool | None = None) -> None:
        self.rows, self.owner, self.counts, self.bound = rows, owner, counts, bound
        # Whether any polygon edge has a radius (those need the slower interval rule).
        self.rounded = bool(rows[RAD, :counts[0]].any()) if rounded is None else rounded


def _kind_slices(counts: tuple[int, ...]) -> list[slice]:
    ends = list(itertools.accumulate(counts))
    return [slice(e - c, e) for c, e in zip(counts, ends)]


def _merge(parts: list[_World]) -> _World:
    """Concatenate the primitive tables kind by kind (bounding circles are not merged)."""
    if len(parts) == 1:
        return parts[0]
    slices = [_kind_slices(w.counts) for w in parts]
    pieces = [(w, sl[k]) for k in range(_KINDS) for w, sl in zip(parts, slices)]
    rows = np.concatenate([w.rows[:, sl] for w, sl in pieces], axis=1)
    owner = np.concatenate([w.owner[sl] for w, sl in pieces])
    counts = tuple(sum(w.counts[k] for w in parts) for k in range(_KINDS))
    return _World(rows, owner, counts, np.empty((3, 0)), any(w.rounded for w in parts))


def _bounding_boxes(world: _World) -> np.ndarray:
    """(4, n_shapes) l, b, r, t of each shape, as cpShapeCacheBB computes them."""
    rows, owner = world.rows, world.owner
    box = np.empty((4, world.bound.shape[1]))
    box[:2], box[2:] = np.inf, -np.inf
    r = rows[RAD]
    for x, y in ((AX, AY), (BX, BY)):
        np.minimum.at(box[0], owner, rows[x] - r)
        np.minimum.at(box[1], owner, rows[y] - r)
        np.maximum.at(box[2], owner, rows[x] + r)
        np.maximum.at(box[3], owner, rows[y] + r)
    return box


def _corner_flags(world: _World, box: np.ndarray) -> _World:
    """Add a flag at every bounding-box corner that (nearly) lies on its shape.

    pymunk tests a static shape only if the query segment meets its bounding box, by a
    rounded slab test. The box test can reject a ray that the shape's exact test accepts
    only if the ray runs (within rounding) along a side line of the box (see _side_flags)
    or through a corner that lies on the shape; rays near a flag are answered by pymunk.
    'Nearly' is generous (1e-6 of the world's size): extra flags only cost time."""
    rows, owner, sl = world.rows, world.owner, _kind_slices(world.counts)
    n = box.shape[1]
    corners = np.stack((box[[0, 2, 2, 0]], box[[1, 1, 3, 3]]))  # (2, 4 corners, n)
    # Distance from each corner to the nearest vertex disc of its shape (an upper bound on
    # the distance to the shape's boundary near a corner).
    gap = np.full((4, n), np.inf)
    for x, y in ((AX, AY), (BX, BY)):
        for c in range(4):
            d = np.hypot(rows[x] - corners[0, c, owner], rows[y] - corners[1, c, owner]) - rows[RAD]
            np.minimum.at(gap[c], owner, d)
    finite = np.isfinite(box).all(axis=0)
    size = 1.0 + (np.abs(box[:, finite]).max() if finite.any() else 0.0)
    c_idx, who = np.nonzero((gap <= 1e-6 * size) & finite)
    flag_rows = np.zeros((_ROWS, who.shape[0]))
    flag_rows[AX] = flag_rows[BX] = corners[0, c_idx, who]
    flag_rows[AY] = flag_rows[BY] = corners[1, c_idx, who]
    order = np.argsort(who, kind="stable")
    pieces = [rows[:, sl[0]], flag_rows[:, order], rows[:, sl[2]], rows[:, sl[3]]]
    owners = [owner[sl[0]], who[order], owner[sl[2]], owner[sl[3]]]
    counts = (world.counts[0], who.shape[0], world.counts[2], world.counts[3])
    return _World(np.concatenate(pieces, axis=1), np.concatenate(owners), counts, world.bound)


class _SceneCache:
    """Static geometry kept in world coordinates; dynamic geometry moved on every cast.

    Rebuilt when the space's shapes change (compared by identity on every cast) or a
    static body's transform changes."""

    def __init__(self, space: pymunk.Space) -> None:
        self.space = space
        self._key: tuple[pymunk.Shape, ...] | None = None

    def invalidate(self) -> None:
        self._key = None

    def world(self) -> tuple[list[_World], np.ndarray]:
        """World primitive tables (static, then moving shapes) and every shape's bounding
        circle (cx, cy, radius) in shape order."""
        key = tuple(self.space.shapes)
        if key != self._key or any(_body_transform(b) != tf for b, tf in self._static_tf.items()):
            self._build(key)
        if not self._bodies:
            return [self._static], self._static.bound
        tf = _transforms(self._handles)
        rows, bound = _moved(self._local.rows, self._local.bound, tf, self._prim_body, self._shape_body)
        moving = _World(rows, self._local.owner, self._local.counts, bound, self._local.rounded)
        return [self._static, moving], np.concatenate((self._static.bound, bound), axis=1)

    def _build(self, key: tuple[pymunk.Shape, ...]) -> None:
        static = [s for s in key if s.body.body_type == pymunk.Body.STATIC]
        dynamic = [s for s in key if s.body.body_type != pymunk.Body.STATIC]
        self.shapes: list[pymunk.Shape] = static + dynamic
        filters = [s.filter for s in self.shapes]
        self.groups = np.array([f.group for f in filters], dtype=np.uint64)
        self.categories = np.array([f.categories for f in filters], dtype=np.uint64)
        self.masks = np.array([f.mask for f in filters], dtype=np.uint64)
        self._admitted: dict[pymunk.ShapeFilter, tuple[np.ndarray, int]] = {}

        collect = _Collector()
        for i, s in enumerate(static):
            collect.add(s, i)
        rows, owner, counts, bound = collect.tables()
        self._static_tf = {b: _body_transform(b) for b in {id(s.body): s.body for s in static}.values()}
        tf = np.array([self._static_tf[s.body] for s in static]).reshape(-1, 4).T
        rows, bound = _moved(rows, bound, tf, owner, np.arange(len(static)))
        static_world = _World(rows, owner, counts, bound)
        box = _bounding_boxes(static_world)
        self._static = _corner_flags(static_world, box)
        # Sorted coordinates of the static boxes' vertical and horizontal side lines.
        finite = np.isfinite(box).all(axis=0)
        self.side_x: list[float] = np.unique(box[[0, 2]][:, finite]).tolist()
        self.side_y: list[float] = np.unique(box[[1, 3]][:, finite]).tolist()

        collect = _Collector()
        for i, s in enumerate(dynamic):
            collect.add(s, len(static) + i)
        self._local = _World(*collect.tables())
        self._bodies = list({id(s.body): s.body for s in dynamic}.values())
        self._handles = [b._body for b in self._bodies]
        slot = {id(b): k for k, b in enumerate(self._bodies)}
        self._shape_body = np.array([slot[id(s.body)] for s in dynamic], dtype=np.intp)
        self._prim_body = self._shape_body[self._local.owner - len(static)]
        self._key = key

    def admitted(self, f: pymunk.ShapeFilter) -> tuple[np.ndarray, int]:
        """Shapes the query filter does not reject (cpShapeFilterReject, negated), and their count."""
        found = self._admitted.get(f)
        if found is None:
            group, cats, qmask = int(f.group), int(f.categories), int(f.mask)
            reject = ((self.groups != 0) & (self.groups == group)) \
                | ((self.categories & qmask) == 0) | ((self.masks & cats) == 0)
            found = self._admitted[f] = (~reject, int(np.count_nonzero(~reject)))
        return found


# ----------------------------------------------------------------------------------------
# One cast
# ----------------------------------------------------------------------------------------

def _trace_rings(parts: list[_World], bound: np.ndarray, keep: np.ndarray, n_keep: int,
                 near: tuple[np.ndarray, ...], fan: _Fan, best: np.ndarray,
                 cast: tuple[float, float, float, float]) -> None:
    """Dense scenes: trace shapes in rings of growing distance. Alphas only decrease, so a
    ray already stopped nearer than a ring's inner radius is left out of that ring, and so
    is every shape whose bounding circle no open ray can reach."""
    gap, dx, dy, dist = near
    ox, oy, rng, scale = cast
    slack = 1e-9 * scale
    first_ring = rng * math.sqrt(_RING_SHAPES / n_keep)
    radii = [-math.inf] + [first_ring * _RING_GROWTH ** k for k in range(_MAX_RINGS - 1)] + [math.inf]
    for k in range(_MAX_RINGS):
        ring = keep & (gap > radii[k]) & (gap <= radii[k + 1])
        rays = fan.every
        if k > 0:
            rays = fan.open(best, (radii[k] - slack) / rng)
            if rays.n == 0:
                return
            cand = np.flatnonzero(ring)
            reach = bound[2, cand] + slack
            half = np.arcsin(np.minimum(reach / dist[cand], 1.0)) + 1e-12
            phi = np.arctan2(dy[cand], dx[cand])
            _, counts = rays.ranges(phi - half, phi + half, dist[cand] <= reach)
            ring[cand[counts == 0]] = False
        if ring.any():
            _Scene(parts, ring, ox, oy, scale, rng, subset=True).trace(fan, rays, best)


class _Rays:
    """Some of the rays, sorted by angle: the angles tiled over three turns, and the ray
    index of each entry. Any interval narrower than 2*pi inside [-3*pi, 3*pi) is then one
    index range with no ray repeated."""

    def __init__(self, theta: np.ndarray, ray: np.ndarray) -> None:
        self.n = theta.shape[0]
        self.theta3 = np.concatenate((theta - _TWO_PI, theta, theta + _TWO_PI))
        self.ray3 = np.concatenate((ray, ray, ray))

    def ranges(self, lo: np.ndarray, hi: np.ndarray, full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """First entry and number of rays inside each [lo, hi] (every ray where full)."""
        first = np.searchsorted(self.theta3, lo, "left")
        stop = np.searchsorted(self.theta3, hi, "right")
        if full.any():
            first[full] = self.n
            stop[full] = 2 * self.n
        return first, stop - first

    def expand(self, first: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ray index of every (interval, ray) pair, interval by interval; and where each
        interval's pairs end."""
        stop = np.cumsum(counts)
        entry = np.arange(int(stop[-1]) if stop.shape[0] else 0) - np.repeat(stop - counts - first, counts)
        return self.ray3[entry], stop


class _Fan:
    """All rays of one cast: end points, and their direction angles in sorted order."""

    def __init__(self, theta: np.ndarray, ends: np.ndarray) -> None:
        n = theta.shape[0]
        self.ends = ends
        drops = np.flatnonzero(theta[1:] < theta[:-1])
        if drops.shape[0] == 0:
            order = np.arange(n)
        elif drops.shape[0] == 1 and theta[-1] <= theta[0]:
            # A sorted fan that wraps past +pi once (e.g. 0..2*pi): rotate instead of sorting.
            order = np.arange(int(drops[0]) + 1, int(drops[0]) + 1 + n)
            order %= n
        else:
            order = np.argsort(theta, kind="stable")
        self.theta, self.order = theta.take(order), order
        self.every = _Rays(self.theta, order)
        self.flagged: list[np.ndarray] = []  # rays passing near a flag (see _corner_flags)

    def open(self, best: np.ndarray, limit: float) -> _Rays:
        """The rays whose current alpha exceeds limit."""
        pos = np.flatnonzero(best[self.order] > limit)
        return _Rays(self.theta[pos], self.order[pos])


class _Scene:
    """Admitted, in-range primitives for one cast from one origin."""

    def __init__(self, parts: list[_World], keep: np.ndarray, ox: float, oy: float, scale: float,
                 rng: float, subset: bool) -> None:
        self.ox, self.oy, self.scale = ox, oy, scale
        # Positional slack [m] and angular margin [rad] for choosing candidate pairs; the
        # second term covers the direction rounding of the segment origin -> end point.
        self.slack = 1e-9 * scale
        self.margin = _EDGE_MARGIN + 1e-15 * scale / rng
        if subset:  # few of the shapes: gather their columns before any arithmetic
            picked = []
            for part in parts:
                idx = np.flatnonzero(keep[part.owner])
                ends = np.searchsorted(idx, np.cumsum(part.counts)).tolist()
                counts = (ends[0], ends[1] - ends[0], ends[2] - ends[1], ends[3] - ends[2])
                picked.append(_World(part.rows.take(idx, axis=1), part.owner.take(idx), counts,
                                     part.bound, part.rounded))
            world = _merge(picked)
            sel = np.ones(world.owner.shape[0], dtype=bool)
        else:
            world = _merge(parts)
            sel = keep[world.owner]
        rows, n_e = world.rows, world.counts[0]
        # Chipmunk's plane test for edges: d = a.n - v0.n - r; the edge is skipped if d < 0.
        dan = np.empty((2, n_e))
        an = np.add(ox * rows[NX, :n_e], oy * rows[NY, :n_e], out=dan[1])
        d = np.subtract(an - rows[VN, :n_e], rows[RAD, :n_e], out=dan[0])
        sel_e = sel[:n_e]
        sel_e &= d >= 0.0
        self.rows = rows.compress(sel, axis=1)  # much faster than rows[:, sel]
        kept = np.cumsum(sel)[[e - 1 for e in itertools.accumulate(world.counts) if e]].tolist()
        kept = [0] * (_KINDS - len(kept)) + kept  # leading empty kinds
        self.ends = kept  # column where each kind ends
        self.n_edges = kept[0]
        dan = dan.compress(sel_e, axis=1)
        # With d > 0 only den > 0 gives t >= 0; d == 0 (origin on the plane) needs Chipmunk's
        # own t >= 0 test, which also passes t = -0.0.
        self.on_plane = not dan[0].all()
        self._intervals(dan[0], world.rounded)
        # From here on RAD and VN hold d and a.n for edges, so that rows RAD: are exactly
        # the per-edge terms of the pair test (d, a.n, nx, ny, dt_min, dt_max).
        self.rows[RAD:VN + 1, :self.n_edges] = dan

    def _intervals(self, d: np.ndarray, rounded: bool) -> None:
        """Ray-angle interval [lo, hi] that can hit each primitive, or the full turn.

        Each primitive is a capsule A-B of radius r. A front-facing edge runs counter-
        clockwise from A (v0) to B (v_prev) as seen from the origin (cross(A-o, B-o) equals
        |edge| * d >= 0); segments are swapped into that order. The A..B arc is widened by
        the half-angle of the wider end disc (radius r + slack), which holds the capsule.
        Rounding moves Chipmunk's hit points by ~1e-15 * scale, far inside these margins.
        An interval wider than a turn needs no flag: it covers every ray (some twice)."""
        rows, ne = self.rows, self.n_edges
        nf_end, seg_start = self.ends[1], self.ends[2]
        rel = rows[:4] - np.array((self.ox, self.oy, self.ox, self.oy))[:, None]
        m = rel.shape[1]
        if seg_start < m:
            s = rel[:, seg_start:]
            flip = s[0] * s[3] - s[1] * s[2] < 0.0
            rel[:, seg_start:] = np.where(flip, s[[2, 3, 0, 1]], s)
        phi = np.arctan2(rel[1::2], rel[0::2])
        span = phi[1] - phi[0]
        span[span < 0.0] += _TWO_PI
        # Origin near an edge's plane: its end points may be near too, and Chipmunk may
        # report t = 0 on any ray when the origin is on the plane; take the full turn.
        # (An origin near a flag is caught by _side_flags.)
        near_edge = d <= _EDGE_NEAR * self.scale
        # Sharp edges and flags: every end point is farther than _EDGE_NEAR * scale, so a
        # fixed angular margin covers the rounding. Everything else gets the positional slack.
        start = 0 if rounded else nf_end
        if start == m:
            half: np.ndarray | float = self.margin
            full = near_edge if ne == m else np.concatenate((near_edge, np.zeros(m - ne, dtype=bool)))
        else:
            full = np.zeros(m, dtype=bool)
            full[:ne] = near_edge
            half = np.full(m, self.margin)
            reach = rows[RAD, start:] + self.slack
            dist = np.hypot(rel[0::2, start:], rel[1::2, start:])
            near = np.minimum(dist[0], dist[1])
            half[start:] += np.arcsin(np.minimum(reach / near, 1.0))
            full[start:] |= near <= reach
            if seg_start < m:
                a, b = rel[:2, seg_start:], rel[2:, seg_start:]
                e = b - a
                u = np.clip(-(a * e).sum(axis=0) / ((e * e).sum(axis=0) + 1e-300), 0.0, 1.0)
                full[seg_start:] |= np.hypot(*(a + u * e)) - rows[RAD, seg_start:] <= self.slack
        self.lo = phi[0] - half
        self.hi = self.lo + (span + 2.0 * half)
        self.full = full

    def trace(self, fan: _Fan, rays: _Rays, best: np.ndarray) -> None:
        """Lower best (alpha per ray) by every hit among the given rays."""
        if self.lo.shape[0] == 0:
            return
        first, counts = rays.ranges(self.lo, self.hi, self.full)
        ray, stop = rays.expand(first, counts)
        ends = self.ends
        p = [0] + [int(stop[e - 1]) if e else 0 for e in ends]  # pair index where each kind ends
        bxy = fan.ends.take(ray, axis=1)
        rows = self.rows
        if p[1]:
            k = np.repeat(rows[RAD:, :ends[0]], counts[:ends[0]], axis=1)
            self._edge_pairs(k, ray[:p[1]], bxy[:, :p[1]], best)
        if p[2] > p[1]:
            fan.flagged.append(ray[p[1]:p[2]])
        if p[3] > p[2]:
            k = np.repeat(rows[:RAD + 1, ends[1]:ends[2]], counts[ends[1]:ends[2]], axis=1)
            self._circle_pairs(k, ray[p[2]:p[3]], bxy[:, p[2]:p[3]], best)
        if p[4] > p[3]:
            k = np.repeat(rows[:NY + 1, ends[2]:], counts[ends[2]:], axis=1)
            self._segment_pairs(k, ray[p[3]:], bxy[:, p[3]:], best)

    def _edge_pairs(self, k: np.ndarray, ray: np.ndarray, bxy: np.ndarray, best: np.ndarray) -> None:
        """cpPolyShapeSegmentQuery's plane test, one (edge, ray) pair per column."""
        d, an, nx, ny, dt_min, dt_max = k
        bx, by = bxy
        den = an - (bx * nx + by * ny)
        t = d / den
        # Chipmunk also rejects t > 1; here such a t cannot lower best (which starts at 1).
        ok = ((np.abs(den) >= _PARALLEL_EPS) & (t >= 0.0)) if self.on_plane else den >= _PARALLEL_EPS
        one_t = 1.0 - t
        dt = nx * (self.oy * one_t + by * t) - ny * (self.ox * one_t + bx * t)
        ok &= (dt_min <= dt) & (dt <= dt_max)
        np.minimum.at(best, ray.compress(ok), t.compress(ok))

    def _circle_pairs(self, k: np.ndarray, ray: np.ndarray, bxy: np.ndarray, best: np.ndarray) -> None:
        """Chipmunk's CircleSegmentQuery with query radius 0."""
        cx, cy, r = k[AX], k[AY], k[RAD]
        t, ok = _circle_alpha(self.ox - cx, self.oy - cy, bxy[0] - cx, bxy[1] - cy, r)
        np.minimum.at(best, ray.compress(ok), t.compress(ok))

    def _segment_pairs(self, k: np.ndarray, ray: np.ndarray, bxy: np.ndarray, best: np.ndarray) -> None:
        """cpSegmentShapeSegmentQuery with query radius 0, including the rounded end caps."""
        ox, oy = self.ox, self.oy
        tax, tay, tbx, tby, r, _, nx, ny = k
        bx, by = bxy
        d = (tax - ox) * nx + (tay - oy) * ny
        pos = d > 0.0
        offx = np.where(pos, -nx, nx) * r - ox
        offy = np.where(pos, -ny, ny) * r - oy
        dx, dy = bx - ox, by - oy
        straddle = (dx * (tay + offy) - dy * (tax + offx)) * (dx * (tby + offy) - dy * (tbx + offx)) <= 0.0
        d_off = d + np.where(pos, -r, r)
        ad = -d_off
        bd = (dx * nx + dy * ny) - d_off
        ok = straddle & (ad * bd < 0.0)
        t = ad / (ad - bd)
        np.minimum.at(best, ray.compress(ok), t.compress(ok))
        c = np.flatnonzero(~straddle & (r != 0.0))
        if c.shape[0]:
            t1, ok1 = _circle_alpha(ox - tax[c], oy - tay[c], bx[c] - tax[c], by[c] - tay[c], r[c])
            t2, ok2 = _circle_alpha(ox - tbx[c], oy - tby[c], bx[c] - tbx[c], by[c] - tby[c], r[c])
            # Chipmunk keeps cap 1 only if its alpha (1.0 when missed) is strictly smaller.
            a1, a2 = np.where(ok1, t1, 1.0), np.where(ok2, t2, 1.0)
            use1 = a1 < a2
            hit = np.where(use1, ok1, ok2)
            np.minimum.at(best, ray[c[hit]], np.where(use1, a1, a2)[hit])


def _circle_alpha(dax: np.ndarray, day: np.ndarray, dbx: np.ndarray, dby: np.ndarray,
                  r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CircleSegmentQuery's alpha and hit flag for da = a - c, db = b - c, rsum = r + 0."""
    aa = dax * dax + day * day
    ab = dax * dbx + day * dby
    bb = dbx * dbx + dby * dby
    qa = aa - 2.0 * ab + bb
    qb = ab - aa
    rsum = r + 0.0
    det = qb * qb - qa * (aa - rsum * rsum)
    t = (-qb - np.sqrt(det)) / qa
    return t, (det >= 0.0) & (t >= 0.0) & (t <= 1.0)  # t <= 1 matters for the caps rule
