"""``RayCaster``: checks, filter and range culling, and the fallbacks to pymunk.

The fast path is skipped wherever rounding could decide pymunk's answer: an origin on or
at a shape's boundary, or next to a bounding-box corner that lies on its shape; single
rays along a static box side or through such a corner are re-asked of pymunk.
"""

from __future__ import annotations

import bisect
import math
import os
from typing import Callable

import numpy as np
import pymunk

from .cache import SceneCache
from .fan import Fan
from .geometry import World
from .reference import check_args, endpoints, reference_cast
from .scene import EDGE_NEAR, Scene, trace_rings

# Rays within this angle [rad] of a box side line through the origin are left to pymunk.
_SIDE_ANGLE = 1e-4
# Up to this many rays, pymunk's own segment_query_first per ray costs less than the fast path's
# fixed cost per cast (measured: the two meet near 40 rays among 20 moving robots).
REFERENCE_RAYS = 40
_NO_SIDES = np.empty((2, 0))
_NO_ORDER = np.empty(0, dtype=np.intp)
# Above this many shapes in range, trace in rings of growing distance (occlusion culling);
# in small worlds the pair tests reject far shapes cheaper than the rings would.
_DENSE_SHAPES = 160


class RayCaster:
    """Casts batches of rays against every shape in a pymunk Space."""

    def __init__(self, space: pymunk.Space, compiled: bool | None = None) -> None:
        """``compiled``: trace with numba (True), with numpy (False), or numba when it can be
        imported and PYMUNK_BOT_NUMBA is not 0 (None). Both give pymunk's answers."""
        self.space = space
        self._cache = SceneCache(space)
        self._kernel = _load_kernel(compiled)

    def cast_many(self, origins: list[tuple[float, float]], angles: list[np.ndarray],
                  max_ranges: list[float], filters: list[pymunk.ShapeFilter]) -> list[np.ndarray]:
        """Many casts at once: what :meth:`cast` gives for each. Compiled, one cast after
        another is cheapest; with numpy, one pass for them all (see :mod:`.batch`)."""
        if self._kernel is not None:
            return [self.cast(*args) for args in zip(origins, angles, max_ranges, filters)]
        from .batch import cast_many
        return cast_many(self, origins, angles, max_ranges, filters)

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
        ox, oy, ang, rng = check_args(origin, angles, max_range)
        n_rays = ang.shape[0]
        if n_rays == 0:
            return np.empty(0)
        if n_rays <= REFERENCE_RAYS:
            return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        cos, sin, ends = endpoints(ox, oy, ang, rng)
        parts, bound, keep, n_keep = self._cache.world(shape_filter)
        # Coordinate scale of this cast: rounding errors are ~1e-16 of it.
        scale = 1.0 + abs(ox) + abs(oy) + rng
        slack = 1e-9 * scale
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
        touch = self.space.point_query_nearest((ox, oy), slack, shape_filter)
        if touch is not None:
            bb = touch.shape.bb
            if touch.distance <= 0.0 and bb.left <= ox <= bb.right and bb.bottom <= oy <= bb.top:
                return np.zeros(n_rays)  # every ray's bounding-box test admits the shape
            # Within rounding of a shape's boundary (distance 0 by underflow, or a hair
            # outside): Chipmunk's plane test may then pass at t = 0 or graze a vertex, and
            # the box test decides ray by ray whether it counts. Let pymunk answer.
            return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        directions = self._side_directions(ox, oy, scale)
        if directions is None:
            # Next to a box corner that may be a flag: its direction is too uncertain.
            return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        best = np.ones(n_rays)
        if self._kernel is not None and n_keep <= _DENSE_SHAPES and len(parts) == 1:
            flagged = self._trace_compiled(parts[0], keep, not dense, ox, oy, scale, rng, sin,
                                           cos, ends, directions, best)
            if flagged is None:
                return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
        else:
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                fan = Fan(np.arctan2(sin, cos), ends)
                if directions:
                    fan.flagged.append(fan.every.expand(*fan.every.ranges(_side_lohi(directions), None))[0])
                if n_keep <= _DENSE_SHAPES:
                    Scene(parts, keep, ox, oy, scale, rng, subset=dense).trace(fan, fan.every, best)
                else:
                    trace_rings(parts, bound, keep, n_keep, rings, fan, best, (ox, oy, rng, scale))
            flagged = np.concatenate(fan.flagged) if fan.flagged else None
        if flagged is not None and flagged.shape[0]:
            # Rays near a box corner or along a box side (see cache.corner_flags): ask pymunk.
            query, start = self.space.segment_query_first, (ox, oy)
            for i in np.unique(flagged).tolist():
                hit = query(start, (ends[0, i], ends[1, i]), 0.0, shape_filter)
                best[i] = 1.0 if hit is None else hit.alpha
        return best * rng

    def _trace_compiled(self, world: World, keep: np.ndarray, cached: bool, ox: float,
                        oy: float, scale: float, rng: float, sin: np.ndarray, cos: np.ndarray,
                        ends: np.ndarray, directions: list[float],
                        best: np.ndarray) -> np.ndarray | None:
        """The compiled tracer on one table: the flagged rays, or None if they overflowed
        its buffer (then pymunk answers the whole cast). ``cached``: keep is a filter's own
        mask (not one culled for this cast), so its columns are kept on the table."""
        found = world.admitted.get(id(keep)) if cached else None
        if found is None or found[0] is not keep:
            found = (keep, keep[world.owner], np.array(world.counts, dtype=np.intp))
            if cached:
                world.admitted[id(keep)] = found
        _, columns, counts = found
        assert self._kernel is not None
        n = best.shape[0]
        flagged = np.empty(4 * n + 64, dtype=np.intp)
        side = _side_lohi(directions) if directions else _NO_SIDES
        args = (world.rows, counts, columns, world.rounded, ox, oy, scale, rng, sin, cos, ends,
                side)
        got = self._kernel(*args, _NO_ORDER, best, flagged)
        if got == -2:  # rays in no simple order: sort them here
            order = np.argsort(np.arctan2(sin, cos), kind="stable")
            got = self._kernel(*args, order, best, flagged)
        return None if got < 0 else flagged[:got]

    def _side_directions(self, ox: float, oy: float, scale: float) -> list[float] | None:
        """Directions [rad] of the rays that may run along a side line of a static bounding
        box (flagged: pymunk answers them); None if the origin is within EDGE_NEAR * scale
        of both a vertical and a horizontal side line (so perhaps of a flag), where no ray
        can be trusted to the fast path.

        A ray along a side line starts (within rounding) on the line and points along it;
        pymunk's box test is then decided by rounding (see cache.corner_flags). The tolerances
        are generous because flagged rays are exact anyway, only slower."""
        near, corner = 1e-7 * scale, EDGE_NEAR * scale
        directions: list[float] = []
        close = 0
        for sides, v, along in ((self._cache.side_x, ox, (-0.5 * math.pi, 0.5 * math.pi)),
                                (self._cache.side_y, oy, (-math.pi, 0.0, math.pi))):
            i = bisect.bisect_left(sides, v - corner)
            if i < len(sides) and sides[i] <= v + corner:
                close += 1
                i = bisect.bisect_left(sides, v - near)
                if i < len(sides) and sides[i] <= v + near:
                    directions.extend(along)
        return None if close == 2 else directions


def _side_lohi(directions: list[float]) -> np.ndarray:
    """(2, k) angle intervals [rad] around side-line directions."""
    return np.array(([a - _SIDE_ANGLE for a in directions], [a + _SIDE_ANGLE for a in directions]))


def _load_kernel(compiled: bool | None) -> Callable[..., int] | None:
    """The compiled tracer, unless ``compiled`` is False (or None and the environment sets
    PYMUNK_BOT_NUMBA=0) or numba cannot be imported: then None (the numpy path)."""
    if compiled is False or (compiled is None and os.environ.get("PYMUNK_BOT_NUMBA") == "0"):
        return None
    try:
        from .compiled import trace
    except ImportError:
        if compiled:
            raise
        return None
    return trace
