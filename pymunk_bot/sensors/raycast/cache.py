"""Per-space cache of primitive tables: static ones in world coordinates, built once.

pymunk skips a static shape whose bounding box a rounded slab test says the segment
misses; the corner flags and side lines kept here mark the only rays where that test can
disagree with the shape's own, so the caster can hand exactly those rays to pymunk.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import pymunk

from pymunk_bot.sensors.raycast.spaces import Spaces
from pymunk_bot.sensors.raycast.primitives import (AX, AY, BX, BY, RAD, ROWS, BodyReader, Collector, World, body_transform,
                       kind_slices, merge, moved)


def bounding_boxes(world: World) -> np.ndarray:
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


def corner_flags(world: World, box: np.ndarray) -> World:
    """Add a flag at every bounding-box corner that (nearly) lies on its shape.

    pymunk tests a static shape only if the query segment meets its bounding box, by a
    rounded slab test. The box test can reject a ray that the shape's exact test accepts
    only if the ray runs (within rounding) along a side line of the box (see
    RayCaster's _side_flags in caster.py)
    or through a corner that lies on the shape; rays near a flag are answered by pymunk.
    'Nearly' is generous (1e-6 of the world's size): extra flags only cost time."""
    rows, owner, sl = world.rows, world.owner, kind_slices(world.counts)
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
    flag_rows = np.zeros((ROWS, who.shape[0]))
    flag_rows[AX] = flag_rows[BX] = corners[0, c_idx, who]
    flag_rows[AY] = flag_rows[BY] = corners[1, c_idx, who]
    order = np.argsort(who, kind="stable")
    pieces = [rows[:, sl[0]], flag_rows[:, order], rows[:, sl[2]], rows[:, sl[3]]]
    owners = [owner[sl[0]], who[order], owner[sl[2]], owner[sl[3]]]
    counts = (world.counts[0], who.shape[0], world.counts[2], world.counts[3])
    return World(np.concatenate(pieces, axis=1), np.concatenate(owners), counts, world.bound)


def _body(shape: pymunk.Shape) -> pymunk.Body:
    """The body of a shape in a space (pymunk types it Optional: a loose shape has none)."""
    body = shape.body
    if body is None:
        raise ValueError("a shape in the space has no body")
    return body


class _Frame:
    """What one frame (one tick's casts) has computed so far."""

    def __init__(self) -> None:
        self.tf: np.ndarray | None = None  # (4, n) transforms of the moving bodies
        self.moved = 0  # how many of them moved since the previous frame that read them
        self.table: tuple[World, np.ndarray] | None = None  # merged table, bounding circles


class SceneCache:
    """Static geometry kept in world coordinates; dynamic geometry moved on every cast.

    Rebuilt when the space's shapes change (compared by identity on every cast; the same
    shapes in another order, as robots moving between Spaces leave them, are no change) or a
    static body's transform changes."""

    def __init__(self, space: "pymunk.Space | Spaces",
                 move_into: Callable[..., None] | None = None) -> None:
        """``space``: a pymunk Space, or several as one (:class:`~.spaces.Spaces`);
        ``move_into``: the compiled mover (compiled.move_into), or None to move with numpy."""
        self.space = space
        self._move_into = move_into
        self._key: tuple[pymunk.Shape, ...] | None = None
        self._static_shapes: list[pymunk.Shape] | None = None  # those the static tables hold
        self._static_tf: dict[pymunk.Body, tuple[float, float, float, float]] = {}
        self._framed = False  # True once frames are used: the scene is frozen between them
        self._frame: _Frame | None = None  # this frame's scene, built on demand
        self._last_tf: np.ndarray | None = None  # moving bodies' transforms when last read

    def invalidate(self) -> None:
        self._key = self._static_shapes = None
        self._frame = None

    def begin_frame(self) -> None:
        """Bodies have moved (a physics step): until the next call, every cast sees this same
        scene, so moving shapes are transformed, and shapes checked for changes, once."""
        self._framed = True
        self._frame = None

    def world(self, f: pymunk.ShapeFilter) -> tuple[list[World], np.ndarray, np.ndarray, int]:
        """World primitive tables (static, then moving shapes), every shape's bounding circle
        (cx, cy, radius) in shape order, and the shapes the filter admits with their count.

        Moving shapes the filter rejects are not moved: a robot's LiDAR never sees its own
        body, so in a world where only robots move that skips the per-cast transform."""
        if not self._framed or self._frame is None:
            key = tuple(self.space.shapes)
            if key != self._key and self._key is not None and len(key) == len(self._key) \
                    and set(key) == set(self._key):
                self._key = key  # the same shapes in another order (robots that changed Space)
            if key != self._key or self._static_moved():
                self._build(key)
            self._frame = _Frame()
        keep, n_keep, static_keep, n_static_keep = self._admitted_for(f)
        if static_keep is not None:  # the filter admits nothing that moves
            return [self._static], self._static.bound, static_keep, n_static_keep
        if not self._bodies:  # nothing moves: the static table is all there is
            return [self._static], self._static.bound, keep, n_keep
        merged, bounds = self._moving_table(keep)
        return [merged], bounds, keep, n_keep

    def scene(self) -> tuple[World, np.ndarray]:
        """This frame's table of every shape (static and moving) and every shape's bounding
        circle, whatever the filter: for tracers that apply filters themselves (their
        groups, categories and masks are ``groups``, ``categories``, ``masks``, per shape)."""
        if not self._framed or self._frame is None:
            self.world(pymunk.ShapeFilter())  # checks the shapes, starts the frame
        if not self._bodies:
            return self._static, self._static.bound
        frame = self._frame
        assert frame is not None
        if frame.table is None:
            frame.table = self._merged(self._read_bodies(frame))
        return frame.table

    def _read_bodies(self, frame: _Frame) -> np.ndarray:
        """The moving bodies' transforms in this frame (read once), and how many moved."""
        if frame.tf is None:
            frame.tf = tf = self._reader.read()
            before, self._last_tf = self._last_tf, tf
            frame.moved = (len(self._bodies) if before is None
                           else int(np.count_nonzero((tf != before).any(axis=0))))
        return frame.tf

    def _moving_table(self, keep: np.ndarray) -> tuple[World, np.ndarray]:
        """The static and moving primitives in one table, with every shape's bounding circle.

        A filter whose admitted bodies have not moved since its last cast (a crate at rest,
        parked robots) gets that cast's table again, and with it the per-filter selections
        cached on the table; the shapes it rejects may be stale there, which it never sees."""
        frame = self._frame
        assert frame is not None
        tf = self._read_bodies(frame)
        seen, unseen = self._body_admitted(keep)
        # More bodies moved since the last frame that read them than this filter ignores:
        # one it sees has moved (the usual case in a fleet), so skip the exact comparison.
        now = None if frame.moved > unseen else tf[:, seen]
        last = self._resting.get(id(keep))
        if now is not None and last is not None and last[0] is keep and np.array_equal(last[1], now):
            return last[2]
        if frame.table is None:
            frame.table = self._merged(tf)
        if now is not None:
            self._resting[id(keep)] = (keep, now, frame.table)
        return frame.table

    def _merged(self, tf: np.ndarray) -> tuple[World, np.ndarray]:
        """The static table and the moving one, moved by ``tf``, merged kind by kind; and
        every shape's bounding circle."""
        if self._move_into is None:
            rows, bound = moved(self._local.rows, self._local.bound, tf, self._prim_body,
                                self._shape_body)
            moving = World(rows, self._local.owner, self._local.counts, bound, self._local.rounded)
            return merge([self._static, moving]), np.concatenate((self._static.bound, bound), axis=1)
        template, bounds = self._template
        rows, bound = template.rows.copy(), bounds.copy()
        self._move_into(self._local.rows, self._local.bound, tf, self._prim_body,
                        self._shape_body, self._dest, self._static.bound.shape[1], rows, bound)
        return World(rows, template.owner, template.counts, template.bound, template.rounded), bound

    def _body_admitted(self, keep: np.ndarray) -> tuple[np.ndarray, int]:
        """Which moving bodies have a shape the filter admits (bool per body), and how many
        have none."""
        found = self._seen.get(id(keep))
        if found is None or found[0] is not keep:
            seen = np.zeros(len(self._bodies), dtype=bool)
            n_static = len(self.shapes) - len(self._shape_body)
            seen[self._shape_body[keep[n_static:]]] = True
            found = self._seen[id(keep)] = (keep, seen, len(self._bodies) - int(seen.sum()))
        return found[1], found[2]

    def _build(self, key: tuple[pymunk.Shape, ...]) -> None:
        static = [s for s in key if _body(s).body_type == pymunk.Body.STATIC]
        dynamic = [s for s in key if _body(s).body_type != pymunk.Body.STATIC]
        self.shapes: list[pymunk.Shape] = static + dynamic
        filters = [s.filter for s in self.shapes]
        self.groups = np.array([f.group for f in filters], dtype=np.uint64)
        self.categories = np.array([f.categories for f in filters], dtype=np.uint64)
        self.masks = np.array([f.mask for f in filters], dtype=np.uint64)
        # (group, categories, mask) of every shape, for tracers that filter by themselves.
        self.shape_filters = np.stack((self.groups, self.categories, self.masks)).reshape(3, -1)
        self._admitted: dict[pymunk.ShapeFilter,
                             tuple[np.ndarray, int, np.ndarray | None, int]] = {}

        if static != self._static_shapes or self._static_moved():
            self._build_static(static)  # else the same fixed shapes where they were: kept

        collect = Collector()
        for i, s in enumerate(dynamic):
            collect.add(s, len(static) + i)
        self._local = World(*collect.tables())
        self._bodies = list({id(_body(s)): _body(s) for s in dynamic}.values())
        self._reader = BodyReader(self.space, self._bodies)
        slot = {id(b): k for k, b in enumerate(self._bodies)}
        self._shape_body = np.array([slot[id(s.body)] for s in dynamic], dtype=np.intp)
        self._prim_body = self._shape_body[self._local.owner - len(static)]
        if self._move_into is not None:
            # The merged layout, fixed until the shapes change: static columns then moving
            # ones, kind by kind; dest is where each moving column lands.
            self._template = (merge([self._static, self._local]),
                              np.concatenate((self._static.bound, self._local.bound), axis=1))
            ends_s = np.cumsum(self._static.counts)
            ends_m = np.cumsum(self._local.counts)
            kind = np.searchsorted(ends_m, np.arange(ends_m[-1]), side="right")
            start_m = ends_m - np.asarray(self._local.counts)
            self._dest = (ends_s[kind] + start_m[kind]
                          + (np.arange(ends_m[-1]) - start_m[kind])).astype(np.intp)
        # Per filter (keyed by its admitted array, kept alive here): the table of its last
        # cast with the transforms of the bodies it sees then; and which bodies it sees.
        self._resting: dict[int, tuple[np.ndarray, np.ndarray, tuple[World, np.ndarray]]] = {}
        self._seen: dict[int, tuple[np.ndarray, np.ndarray, int]] = {}
        self._last_tf = None  # moving bodies' transforms when last read
        self._key = key

    def _static_moved(self) -> bool:
        """Whether a static body has moved since the static tables were built."""
        return any(body_transform(b) != tf for b, tf in self._static_tf.items())

    def _build_static(self, static: list[pymunk.Shape]) -> None:
        """The static shapes' tables in world coordinates, their bounding boxes, corner flags
        and side lines (built again only when a static shape comes, goes or moves: a copy of
        a scenario rebuilt among others changes moving shapes alone)."""
        collect = Collector()
        for i, s in enumerate(static):
            collect.add(s, i)
        rows, owner, counts, bound = collect.tables()
        self._static_tf = {b: body_transform(b)
                           for b in {id(_body(s)): _body(s) for s in static}.values()}
        tf = np.array([self._static_tf[_body(s)] for s in static]).reshape(-1, 4).T
        rows, bound = moved(rows, bound, tf, owner, np.arange(len(static)))
        static_world = World(rows, owner, counts, bound)
        box = bounding_boxes(static_world)
        self.static_boxes = box  # (4, n_static) l, b, r, t [m]
        self._static = corner_flags(static_world, box)
        # Sorted coordinates of the static boxes' vertical and horizontal side lines.
        finite = np.isfinite(box).all(axis=0)
        self.side_x: list[float] = np.unique(box[[0, 2]][:, finite]).tolist()
        self.side_y: list[float] = np.unique(box[[1, 3]][:, finite]).tolist()
        self.side_lines = (np.array(self.side_x), np.array(self.side_y))  # the same, as arrays
        self._static_shapes = static

    def _admitted_for(self, f: pymunk.ShapeFilter) -> tuple[np.ndarray, int, np.ndarray | None, int]:
        """Shapes the query filter does not reject (cpShapeFilterReject, negated) and their
        count; then the same for the static shapes alone if the filter rejects every moving
        shape (else None, 0). Cached per filter: the arrays' identity keys later caches."""
        found = self._admitted.get(f)
        if found is None:
            group, cats, qmask = int(f.group), int(f.categories), int(f.mask)
            reject = ((self.groups != 0) & (self.groups == group)) \
                | ((self.categories & qmask) == 0) | ((self.masks & cats) == 0)
            keep = ~reject
            n_static = len(self.shapes) - len(self._shape_body)
            static_keep = None if keep[n_static:].any() else keep[:n_static].copy()
            found = self._admitted[f] = (
                keep, int(np.count_nonzero(keep)), static_keep,
                0 if static_keep is None else int(np.count_nonzero(static_keep)))
        return found
