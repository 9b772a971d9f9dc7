"""``RayCaster``: checks, filter and range culling, and the fallbacks to pymunk.

The fast path is skipped wherever rounding could decide pymunk's answer: an origin on or
at a shape's boundary, or next to a bounding-box corner that lies on its shape; single
rays along a static box side or through such a corner are re-asked of pymunk.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
import pymunk

from pymunk_bot.sensors.raycast.cache import SceneCache
from pymunk_bot.sensors.raycast.fan import Fan
from pymunk_bot.sensors.raycast.primitives import World
from pymunk_bot.sensors.raycast.reference import check_args, endpoints, reference_cast
from pymunk_bot.sensors.raycast.scene import DENSE_SHAPES, Scene, trace_rings
from pymunk_bot.sensors.raycast.sides import side_directions, side_lohi, sides_many
from pymunk_bot.sensors.raycast.spaces import Spaces

# Up to this many rays, pymunk's own segment_query_first per ray costs less than the fast path's
# fixed cost per cast (measured: the two meet near 40 rays among 20 moving robots).
REFERENCE_RAYS = 40
# [m per m of scale] How near a shape's bounding circle an origin must be for the start-inside
# check to ask pymunk: far above rounding (1e-16 of scale), far below any robot's size.
NEAR_SHAPE = 1e-6
# The same for the compiled tracer: its fixed cost per cast (about 20 us) buys ~6 of pymunk's rays.
COMPILED_REFERENCE_RAYS = 6
_MAX_CACHED = 4096  # query filters (one per robot, usually) and scratch sizes remembered
_NO_SIDES = np.zeros((1, 2, 0))  # the tracer's side intervals when no ray runs along a side
_NO_SIDE_COUNT = np.zeros(1, dtype=np.intp)
_NO_ORDER = np.empty((1, 0), dtype=np.intp)  # the tracer's ray order when it needs none


@dataclass(slots=True)
class _Job:
    """A cast for the fast path: checked arguments, the scene it sees, its side-line rays."""

    ox: float  # origin [m]
    oy: float
    ang: np.ndarray  # world-frame ray angles [rad]
    rng: float  # max range [m]
    filter: pymunk.ShapeFilter
    parts: list[World]  # the primitive tables
    bound: np.ndarray  # every shape's bounding circle (cx, cy, r) [m]
    keep: np.ndarray  # the shapes to trace
    n_keep: int
    scale: float  # coordinate scale [m]: rounding errors are ~1e-16 of it
    directions: list[float]  # side-line directions [rad]: rays there are asked of pymunk
    rings: tuple[np.ndarray, ...] | None  # numpy's dense scenes: (gap, dx, dy, dist) per shape
    dense: bool  # numpy's dense scenes: keep was culled by distance


class RayCaster:
    """Casts batches of rays against every shape in a pymunk Space."""

    def __init__(self, space: "pymunk.Space | Spaces", compiled: bool | None = None) -> None:
        """``space``: a pymunk Space, or several cast against as one (:class:`~.spaces.Spaces`:
        a world's robots that step apart); ``compiled``: trace with numba (True), with numpy
        (False), or numba when it can be imported and PYMUNK_BOT_NUMBA is not 0 (None). Both
        give pymunk's answers."""
        self.space = space
        self._kernel = _load_kernel(compiled)
        mover: Callable[..., None] | None = None
        if self._kernel is not None:
            from pymunk_bot.sensors.raycast.compiled import move_into as mover
            from pymunk_bot.sensors.raycast.compiled import endpoints_rows, near_admitted
            self._near_admitted, self._endpoints_rows = near_admitted, endpoints_rows
        self._cache = SceneCache(space, mover)
        self._filter_rows: dict[pymunk.ShapeFilter, np.ndarray] = {}
        # A single cast's origin x, y, max range and scale (filled, then read by the tracer).
        self._one = tuple(np.empty(1) for _ in range(4))
        self._scratch: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}

    def _filter_row(self, f: pymunk.ShapeFilter) -> np.ndarray:
        """(group, categories, mask) of a query filter, as the tracer takes them (uint64)."""
        row = self._filter_rows.get(f)
        if row is None:
            if len(self._filter_rows) >= _MAX_CACHED:
                self._filter_rows.clear()
            row = self._filter_rows[f] = np.array(f, dtype=np.uint64)  # (group, categories, mask)
        return row

    def _buffers(self, k: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The tracer's scratch for k casts of n rays: flagged-ray lists and their counts
        (read before the next call, so one pair serves every call of that size)."""
        found = self._scratch.get((k, n))
        if found is None:
            if len(self._scratch) >= _MAX_CACHED:
                self._scratch.clear()
            found = self._scratch[(k, n)] = (np.empty((k, 4 * n + 64), dtype=np.intp),
                                             np.empty(k, dtype=np.intp))
        return found

    def cast_many(self, origins: Sequence[tuple[float, float]] | np.ndarray,
                  angles: Sequence[np.ndarray] | np.ndarray,
                  max_ranges: Sequence[float] | np.ndarray, filters: list[pymunk.ShapeFilter],
                  filter_rows: np.ndarray | None = None) -> list[np.ndarray] | np.ndarray:
        """Many casts at once: what :meth:`cast` gives for each, with less work per cast
        (compiled: one tracer call for every cast on the same table and ray count; numpy:
        one pass for them all, see :mod:`.batch`). ``filter_rows``: the filters as (K, 3)
        uint64 rows (group, categories, mask), when the caller keeps them."""
        if self._kernel is None:
            from pymunk_bot.sensors.raycast.batch import cast_many
            return cast_many(self, origins, angles, max_ranges, filters)
        if len(origins) > 1:
            uniform = _uniform(origins, angles, max_ranges)
            if uniform is not None:
                return self._cast_uniform(*uniform, list(filters), filter_rows)
        out: list[np.ndarray | None] = []
        groups: dict[tuple[int, int], list[tuple[int, _Job]]] = {}
        for i, args in enumerate(zip(origins, angles, max_ranges, filters)):
            job = self._prepare(*args)
            out.append(job if isinstance(job, np.ndarray) else None)
            if isinstance(job, _Job):
                groups.setdefault((id(job.parts[0]), job.ang.shape[0]), []).append((i, job))
        for members in groups.values():
            jobs = [job for _, job in members]
            for (i, _), ranges in zip(members, self._trace_compiled(jobs)):
                out[i] = ranges
        return [r if r is not None else np.empty(0) for r in out]

    def _cast_uniform(self, xy: np.ndarray, ang: np.ndarray, rng: np.ndarray,
                      filters: list[pymunk.ShapeFilter], f_all: np.ndarray | None = None
                      ) -> list[np.ndarray] | np.ndarray:
        """cast_many for checked casts with one ray count: the pymunk queries per origin, all
        else one array operation or one tracer call for them all."""
        assert self._kernel is not None
        k, n = ang.shape
        table, bound = self._cache.scene()  # first: it also checks the shapes for changes
        ox, oy = xy[:, 0].copy(), xy[:, 1].copy()
        scale = 1.0 + np.abs(ox) + np.abs(oy) + rng  # [m] rounding errors are ~1e-16 of it
        sides, n_sides, cornered = sides_many(self._cache, ox, oy, scale)
        if f_all is None:
            f_all = np.array(filters, dtype=np.uint64).reshape(-1, 3)  # as _filter_row reads them
        near = np.empty(k, dtype=np.bool_)  # pymunk is asked only about origins near a shape
        self._near_admitted(self._cache.static_boxes, bound, self._cache.shape_filters, ox, oy,
                            NEAR_SHAPE * scale, f_all, near)
        # Origins at a shape (the start-inside rule) or a box corner: the single cast's path.
        query = self.space.point_query_nearest
        single = [i for i in np.flatnonzero(cornered | near).tolist() if cornered[i] or query(
            (float(ox[i]), float(oy[i])), float(1e-9 * scale[i]), filters[i]) is not None]
        out: list[np.ndarray | None] = [None] * k
        for i in single:
            out[i] = self.cast((float(ox[i]), float(oy[i])), ang[i], float(rng[i]), filters[i])
        traced = np.setdiff1d(np.arange(k), single) if single else np.arange(k)
        if single:
            ox, oy, ang, rng, scale = ox[traced], oy[traced], ang[traced], rng[traced], scale[traced]
            sides, n_sides = sides[traced], n_sides[traced]
        ends = np.empty((ang.shape[0], 2, n))
        self._endpoints_rows(ox, oy, ang, rng, ends)  # endpoints_many's, compiled
        f = f_all[traced] if single else f_all
        best = np.ones((traced.shape[0], n))
        flagged, got = self._buffers(traced.shape[0], n)
        self._kernel(table.rows, table.count_array, table.owner, bound,
                     self._cache.shape_filters, table.rounded, ox, oy, scale, rng, f, ang, ends,
                     sides, n_sides, _no_order(traced.shape[0]), best, flagged, got)
        counts = got.tolist()  # read now: a cast below may reuse the tracer's scratch
        ranges = best * rng[:, None]  # _finish's product, for the casts without flagged rays
        if not single and not any(counts):  # the usual case: every cast traced, none flagged
            return ranges  # (K, n): row k is cast k's
        for row, (i, count) in enumerate(zip(traced.tolist(), counts)):
            if count == 0:
                out[i] = ranges[row]
                continue
            start = (float(ox[row]), float(oy[row]))
            if count < 0:  # rays in no simple order, or too many flagged: the single cast
                out[i] = self.cast(start, ang[row], float(rng[row]), filters[i])
            else:
                out[i] = self._finish(start, filters[i], float(rng[row]), ends[row], best[row],
                                      flagged[row, :count])
        return [r if r is not None else np.empty(0) for r in out]

    @property
    def scene_cache(self) -> SceneCache:
        """The cached view of the scene that casts share (the batched casts read it too)."""
        return self._cache

    def begin_frame(self) -> None:
        """Bodies have moved: casts until the next call share one view of the scene (the
        simulation calls this once per tick before its LiDARs read)."""
        self._cache.begin_frame()

    def invalidate(self) -> None:
        """Drop cached geometry; needed only after changing a shape's filter, size or vertices,
        or a body's type, without adding or removing a shape."""
        self._cache.invalidate()

    def cast(self, origin: tuple[float, float], angles: np.ndarray, max_range: float,
             shape_filter: pymunk.ShapeFilter = pymunk.ShapeFilter()) -> np.ndarray:
        """Distance along each ray (world-frame angles [rad]) from origin to the first shape the
        filter admits; max_range where nothing is hit within max_range. float64 array, len(angles)."""
        job = self._prepare(origin, angles, max_range, shape_filter)
        if isinstance(job, np.ndarray):
            return job
        if self._kernel is not None:
            return self._trace_compiled([job])[0]
        ox, oy, rng, n_keep = job.ox, job.oy, job.rng, job.n_keep
        cos, sin, ends = endpoints(ox, oy, job.ang, rng)
        best = np.ones(job.ang.shape[0])
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            fan = Fan(np.arctan2(sin, cos), ends)
            if job.directions:
                lohi = side_lohi(job.directions)
                fan.flagged.append(fan.every.expand(*fan.every.ranges(lohi, None))[0])
            if n_keep <= DENSE_SHAPES:
                Scene(job.parts, job.keep, ox, oy, job.scale, rng, subset=job.dense).trace(
                    fan, fan.every, best)
            else:
                assert job.rings is not None  # set with dense, which n_keep > DENSE_SHAPES implies
                trace_rings(job.parts, job.bound, job.keep, n_keep, job.rings, fan, best,
                            (ox, oy, rng, job.scale))
        return self._finish((ox, oy), job.filter, rng, ends, best,
                            np.concatenate(fan.flagged) if fan.flagged else None)

    def _prepare(self, origin: tuple[float, float], angles: np.ndarray, max_range: float,
                 shape_filter: pymunk.ShapeFilter) -> np.ndarray | _Job:
        """The answer where it needs no tracing (or only pymunk can give it); else the job."""
        ox, oy, ang, rng = check_args(origin, angles, max_range)
        n_rays = ang.shape[0]
        if n_rays == 0:
            return np.empty(0)
        compiled = self._kernel is not None
        if n_rays <= (COMPILED_REFERENCE_RAYS if compiled else REFERENCE_RAYS):
            return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        parts, bound, keep, n_keep = self._cache.world(shape_filter)
        # Coordinate scale of this cast: rounding errors are ~1e-16 of it.
        scale = 1.0 + abs(ox) + abs(oy) + rng
        slack = 1e-9 * scale
        # The compiled tracer culls shapes out of range itself, for less than numpy's cost.
        dense = n_keep > DENSE_SHAPES and not compiled
        rings = None
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
        touch = self.space.point_query_nearest((ox, oy), slack, shape_filter)
        if touch is not None:
            bb = touch.shape.bb
            if touch.distance <= 0.0 and bb.left <= ox <= bb.right and bb.bottom <= oy <= bb.top:
                return np.zeros(n_rays)  # every ray's bounding-box test admits the shape
            # Within rounding of a shape's boundary (distance 0 by underflow, or a hair
            # outside): Chipmunk's plane test may then pass at t = 0 or graze a vertex, and
            # the box test decides ray by ray whether it counts. Let pymunk answer.
            return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        directions = side_directions(self._cache, ox, oy, scale)
        if directions is None:
            # Next to a box corner that may be a flag: its direction is too uncertain.
            return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        return _Job(ox=ox, oy=oy, ang=ang, rng=rng, filter=shape_filter, parts=parts,
                    bound=bound, keep=keep, n_keep=n_keep, scale=scale, directions=directions,
                    rings=rings, dense=dense)

    def _finish(self, start: tuple[float, float], shape_filter: pymunk.ShapeFilter,
                max_range: float, ends: np.ndarray, best: np.ndarray,
                flagged: np.ndarray | None) -> np.ndarray:
        """Ranges from alphas, after pymunk answers the flagged rays: those near a box corner
        or along a box side (see cache.corner_flags)."""
        if flagged is not None and flagged.shape[0]:
            query = self.space.segment_query_first
            for i in np.unique(flagged).tolist():
                hit = query(start, (ends[0, i], ends[1, i]), 0.0, shape_filter)
                best[i] = 1.0 if hit is None else hit.alpha
        return best * max_range

    def _trace_compiled(self, jobs: list[_Job], order: np.ndarray | None = None
                        ) -> list[np.ndarray]:
        """Ranges of casts on one table with one ray count, by the compiled tracer (one call
        for all of them); ``order``: the rays' angle order, for a single cast whose rays are
        not one turn in order (the tracer asks for it)."""
        assert self._kernel is not None
        world, bound = jobs[0].parts[0], jobs[0].bound
        k, n = len(jobs), jobs[0].ang.shape[0]
        # Per cast: origin x, y [m], max range [m], coordinate scale [m].
        if k == 1:  # a LiDAR's own cast: without the batch's array set-up
            job = jobs[0]
            ox, oy, rng, scale = self._one
            ox[0], oy[0], rng[0], scale[0] = job.ox, job.oy, job.rng, job.scale
            angles = job.ang[None]
            filters = self._filter_row(job.filter)[None]
        else:
            ox, oy, rng, scale = np.array([[job.ox for job in jobs], [job.oy for job in jobs],
                                           [job.rng for job in jobs], [job.scale for job in jobs]])
            angles = np.stack([job.ang for job in jobs])
            filters = np.concatenate([self._filter_row(job.filter)[None] for job in jobs])
        ends = np.empty((k, 2, n))
        self._endpoints_rows(ox, oy, angles, rng, ends)  # endpoints_many's, compiled
        counts = [len(job.directions) for job in jobs]
        if k == 1 and not counts[0]:
            n_sides, sides = _NO_SIDE_COUNT, _NO_SIDES
        elif any(counts):
            n_sides = np.array(counts, dtype=np.intp)
            sides = np.zeros((k, 2, max(counts)))
            for row, job in zip(sides, jobs):
                if job.directions:
                    row[:, :len(job.directions)] = side_lohi(job.directions)
        else:
            n_sides = np.zeros(k, dtype=np.intp)
            sides = _NO_SIDES if k == 1 else np.zeros((k, 2, 0))
        best = np.ones((k, n))
        flagged, got = self._buffers(k, n)
        self._kernel(world.rows, world.count_array, world.owner, bound,
                     self._cache.shape_filters, world.rounded, ox, oy, scale, rng, filters,
                     angles, ends, sides, n_sides,
                     _no_order(k) if order is None else order[None], best, flagged, got)
        out = []
        for job, row, ray_ends, flags, count in zip(jobs, best, ends, flagged, got.tolist()):
            if count == -2:  # rays in no simple order: sort them, trace this cast again
                order = np.argsort(_wrapped(job.ang), kind="stable")
                out.append(self._trace_compiled([job], order)[0])
            elif count < 0:  # more flagged rays than the buffer holds: pymunk answers
                out.append(reference_cast(self.space, (job.ox, job.oy), job.ang, job.rng,
                                          job.filter))
            else:
                out.append(self._finish((job.ox, job.oy), job.filter, job.rng, ray_ends, row,
                                        flags[:count]))
        return out


def _uniform(origins: Sequence[tuple[float, float]] | np.ndarray,
             angles: Sequence[np.ndarray] | np.ndarray, max_ranges: Sequence[float] | np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Casts as arrays (origins (K, 2), angles (K, n), ranges (K,)) if they share a ray
    count above COMPILED_REFERENCE_RAYS and pass check_args' checks; else None."""
    try:
        xy = np.array(origins, dtype=np.float64)
        ang = np.asarray(angles, dtype=np.float64)  # no copy when it is one already
        rng = np.array(max_ranges, dtype=np.float64)
    except (TypeError, ValueError):  # ragged or not numbers: the single casts say what is wrong
        return None
    k = len(origins)
    if (xy.shape != (k, 2) or ang.ndim != 2 or rng.shape != (k,)
            or ang.shape[1] <= COMPILED_REFERENCE_RAYS):
        return None
    if not (np.isfinite(xy).all() and np.isfinite(ang).all() and np.isfinite(rng).all()
            and (rng > 0.0).all()):
        return None
    return xy, ang, rng


def _no_order(k: int) -> np.ndarray:
    """The tracer's ray-order argument for k casts whose rays need no given order."""
    return _NO_ORDER if k == 1 else np.empty((k, 0), dtype=np.intp)


def _wrapped(ang: np.ndarray) -> np.ndarray:
    """Angles [rad] wrapped to [-pi, pi) by the compiled tracer's own arithmetic, so that an
    order sorted here is sorted there."""
    two_pi = 2.0 * math.pi
    return ang - two_pi * np.floor((ang + math.pi) / two_pi)


def _load_kernel(compiled: bool | None) -> Callable[..., None] | None:
    """The compiled tracer, unless ``compiled`` is False (or None and the environment sets
    PYMUNK_BOT_NUMBA=0) or numba cannot be imported: then None (the numpy path)."""
    if compiled is False or (compiled is None and os.environ.get("PYMUNK_BOT_NUMBA") == "0"):
        return None
    try:
        from pymunk_bot.sensors.raycast.compiled import trace_filtered
    except ImportError:
        if compiled:
            raise
        return None
    return trace_filtered
