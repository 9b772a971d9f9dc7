"""Primitive tables: pymunk shapes as columns of Chipmunk's own per-primitive numbers.

Every shape becomes capsules A-B of radius RAD, one column each, grouped by kind, with
world coordinates computed by Chipmunk's transform arithmetic in Chipmunk's order, so
every later test sees the very floats Chipmunk would.
"""

from __future__ import annotations

import itertools
import math
import sys

import numpy as np
import pymunk
import pymunk.batch as batch

from pymunk_bot.sensors.raycast.spaces import Spaces

# cpvnormalize adds CPFLOAT_MIN (DBL_MIN) to the length; kept for bit-equal normals.
_DBL_MIN = sys.float_info.min
# From this many moving bodies, one pymunk.batch read beats reading them one by one.
_BATCH_BODIES = 4

# Rows of a primitive table (one column per primitive). Every primitive is a capsule A-B
# of radius RAD; the kinds are stored contiguously in this order:
#   edge:    A = vertex i, B = vertex i-1, N = plane normal, VN = A.N, RAD = poly radius,
#            DTMIN = cross(N, B), DTMAX = cross(N, A)       (cpPolyShapeSegmentQuery terms)
#   flag:    A = B = a corner of a static shape's bounding box that lies on the shape (see
#            cache.corner_flags); rays through it are handed to pymunk itself
#   circle:  A = B = centre (also the rounded corners of polys with a radius)
#   segment: A, B = end points, N = the segment's normal
AX, AY, BX, BY, RAD, VN, NX, NY, DTMIN, DTMAX = range(10)
RAW = [AX, AY, BX, BY, RAD, NX, NY]  # the rows Collector fills
ROWS = 10
KINDS = 4



def body_transform(body: pymunk.Body) -> tuple[float, float, float, float]:
    """(cos, sin, tx, ty) of the body's transform, read exactly through pymunk's public API
    (``rotation_vector`` is the transform's (a, b), ``position`` its (tx, ty))."""
    rot, pos = body.rotation_vector, body.position
    return rot.x, rot.y, pos.x, pos.y


def transforms(bodies: list[pymunk.Body]) -> np.ndarray:
    """(4, n) cos, sin, tx, ty of many bodies, as body_transform."""
    out: list[float] = []
    add = out.extend
    for body in bodies:
        rot, pos = body.rotation_vector, body.position
        add((rot.x, rot.y, pos.x, pos.y))
    # C order, as BodyReader.read gives: one array layout for the kernels that move tables
    return np.ascontiguousarray(np.array(out).reshape(-1, 4).T)


class BodyReader:
    """:func:`transforms` of a fixed list of bodies, read in one ``pymunk.batch`` call per
    Space (``space``: a pymunk Space, or :class:`~.spaces.Spaces`).

    The batch gives each body's position (the transform's translation, as ``position``) and
    angle; the rotation is Chipmunk's ``cpvforangle`` of that angle, the C library's cos and
    sin, which ``math.cos`` and ``math.sin`` are too. Checked against ``rotation_vector``
    when made: where the two disagree, every read goes body by body.
    """

    FIELDS = batch.BodyFields.BODY_ID | batch.BodyFields.POSITION | batch.BodyFields.ANGLE

    def __init__(self, space: "pymunk.Space | Spaces", bodies: list[pymunk.Body]) -> None:
        self.spaces = space.spaces if isinstance(space, Spaces) else (space,)
        self.bodies = bodies
        self._ids = np.array([b.id for b in bodies], dtype=np.uintp)
        self._rows: np.ndarray | None = None  # where each body sits in the batches' order
        self._buffers = [batch.Buffer() for _ in self.spaces]
        self.batched = len(bodies) >= _BATCH_BODIES and all(
            (math.cos(b.angle), math.sin(b.angle)) == tuple(b.rotation_vector) for b in bodies)

    def read(self) -> np.ndarray:
        """(4, n) cos, sin, tx, ty of the bodies now."""
        if not self.batched:
            return transforms(self.bodies)
        ids_read, states = [], []
        for space, buffer in zip(self.spaces, self._buffers):
            buffer.clear()
            batch.get_space_bodies(space, self.FIELDS, buffer)
            ids_read.append(np.frombuffer(buffer.int_buf(), dtype=np.uintp))
            states.append(np.frombuffer(buffer.float_buf()).reshape(-1, 3))
        ids = ids_read[0] if len(ids_read) == 1 else np.concatenate(ids_read)
        rows = self._rows
        if rows is None or rows.shape[0] and (rows.max() >= ids.shape[0]
                                              or not np.array_equal(ids[rows], self._ids)):
            # The bodies came, went or changed Space since: find each one again.
            sorter = np.argsort(ids, kind="stable")
            at = np.searchsorted(ids, self._ids, sorter=sorter)
            if (at >= ids.shape[0]).any() or not np.array_equal(ids[sorter[at]], self._ids):
                raise KeyError("a moving body of the cast scene is in none of its Spaces")
            rows = self._rows = sorter[at]
        xya = (states[0] if len(states) == 1 else np.concatenate(states))[rows]
        angles = xya[:, 2].tolist()
        return np.array(([math.cos(a) for a in angles], [math.sin(a) for a in angles],
                         xya[:, 0], xya[:, 1]))


def moved(rows: np.ndarray, bound: np.ndarray, tf: np.ndarray, prim_body: np.ndarray,
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


class Collector:
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
        rows = np.zeros((ROWS, sum(len(k) for k in self.kinds)))
        raw = [r for kind in self.kinds for r in kind]
        if raw:
            rows[RAW] = np.array(raw, dtype=np.float64).T
        owner = np.array([i for kind in self.owners for i in kind], dtype=np.intp)
        counts = tuple(len(k) for k in self.kinds)
        bound = np.array(self.bound, dtype=np.float64).reshape(-1, 3).T.copy()
        return rows, owner, counts, bound


class World:
    """A primitive table: rows (see AX...), owner shape of each column, column count of each
    kind, and each shape's bounding circle (cx, cy, radius)."""

    def __init__(self, rows: np.ndarray, owner: np.ndarray, counts: tuple[int, ...],
                 bound: np.ndarray, rounded: bool | None = None) -> None:
        self.rows, self.owner, self.counts, self.bound = rows, owner, counts, bound
        self.count_array = np.array(counts, dtype=np.intp)  # the compiled tracer's form
        # Whether any polygon edge has a radius (those need the slower interval rule).
        self.rounded = bool(rows[RAD, :counts[0]].any()) if rounded is None else rounded
        # Cast-independent work on a cached static table (see _static_selection in scene.py).
        self.scratch: np.ndarray | None = None
        self.selections: dict = {}


def kind_slices(counts: tuple[int, ...]) -> list[slice]:
    ends = list(itertools.accumulate(counts))
    return [slice(e - c, e) for c, e in zip(counts, ends)]


def merge(parts: list[World]) -> World:
    """Concatenate the primitive tables kind by kind (bounding circles are not merged)."""
    if len(parts) == 1:
        return parts[0]
    slices = [kind_slices(w.counts) for w in parts]
    pieces = [(w, sl[k]) for k in range(KINDS) for w, sl in zip(parts, slices)]
    rows = np.concatenate([w.rows[:, sl] for w, sl in pieces], axis=1)
    owner = np.concatenate([w.owner[sl] for w, sl in pieces])
    counts = tuple(sum(w.counts[k] for w in parts) for k in range(KINDS))
    return World(rows, owner, counts, np.empty((3, 0)), any(w.rounded for w in parts))

