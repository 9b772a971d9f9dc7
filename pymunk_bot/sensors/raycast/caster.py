"""``RayCaster``: checks, filter and range culling, and the fallbacks to pymunk.

The fast path is skipped wherever rounding could decide pymunk's answer: an origin on or
at a shape's boundary, or next to a bounding-box corner that lies on its shape; single
rays along a static box side or through such a corner are re-asked of pymunk.
"""

from __future__ import annotations

import bisect
import math

import numpy as np
import pymunk

from .cache import SceneCache
from .fan import Fan
from .reference import check_args, endpoints, reference_cast
from .scene import EDGE_NEAR, Scene, trace_rings

# Rays within this angle [rad] of a box side line through the origin are left to pymunk.
_SIDE_ANGLE = 1e-4
# Up to this many rays, pymunk's own segment_query_first per ray costs less than the fast path's
# fixed cost per cast (measured: the two meet near 40 rays among 20 moving robots).
REFERENCE_RAYS = 40
# Above this many shapes in range, trace in rings of growing distance (occlusion culling);
# in small worlds the pair tests reject far shapes cheaper than the rings would.
_DENSE_SHAPES = 160


class RayCaster:
    """Casts batches of rays against every shape in a pymunk Space."""

    def __init__(self, space: pymunk.Space) -> None:
        self.space = space
        self._cache = SceneCache(space)

    def cast_many(self, origins: list[tuple[float, float]], angles: list[np.ndarray],
                  max_ranges: list[float], filters: list[pymunk.ShapeFilter]) -> list[np.ndarray]:
        """Many casts at once (see :mod:`.batch`): what :meth:`cast` gives for each, cheaper
        when many sparse casts are due together."""
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
        best = np.ones(n_rays)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            fan = Fan(np.arctan2(sin, cos), ends)
            if not self._side_flags(fan, ox, oy, scale):
                # Next to a box corner that may be a flag: its direction is too uncertain.
                return reference_cast(self.space, (ox, oy), ang, rng, shape_filter)
            if n_keep <= _DENSE_SHAPES:
                Scene(parts, keep, ox, oy, scale, rng, subset=dense).trace(fan, fan.every, best)
            else:
                trace_rings(parts, bound, keep, n_keep, rings, fan, best, (ox, oy, rng, scale))
        if fan.flagged:
            # Rays near a box corner or along a box side (see cache.corner_flags): ask pymunk.
            query, start = self.space.segment_query_first, (ox, oy)
            for i in np.unique(np.concatenate(fan.flagged)).tolist():
                hit = query(start, (ends[0, i], ends[1, i]), 0.0, shape_filter)
                best[i] = 1.0 if hit is None else hit.alpha
        return best * rng

    def _side_flags(self, fan: Fan, ox: float, oy: float, scale: float) -> bool:
        """Flag the rays that may run along a side line of a static bounding box; False if
        the origin is within EDGE_NEAR * scale of both a vertical and a horizontal side
        line (so perhaps of a flag), where no ray can be trusted to the fast path.

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
        if close == 2:
            return False
        if directions:
            lohi: np.ndarray = np.array(([a - _SIDE_ANGLE for a in directions], [a + _SIDE_ANGLE for a in directions]))
            fan.flagged.append(fan.every.expand(*fan.every.ranges(lohi, None))[0])
        return True
