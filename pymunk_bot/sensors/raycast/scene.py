"""One cast's scene: admitted, in-range primitives, the ray-angle interval each can be hit
in, and the tracing that sends every (primitive, ray) pair in range to an exact kernel.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from pymunk_bot.sensors.raycast.fan import TWO_PI, Fan, Rays
from pymunk_bot.sensors.raycast.primitives import AX, AY, NX, NY, RAD, VN, World, merge
from pymunk_bot.sensors.raycast.kernels import circle_pairs, edge_pairs, segment_pairs

# Candidate rays of a sharp polygon edge: its end points' directions widened by this margin
# [rad], or every ray when the origin is within EDGE_NEAR * scale of the edge's plane.
_EDGE_MARGIN = 1e-7
# Above this many shapes in range, trace in rings of growing distance (occlusion culling);
# in small worlds the pair tests reject far shapes cheaper than the rings would.
DENSE_SHAPES = 160
EDGE_NEAR = 1e-5
# Trace in rings of growing distance (occlusion culling): about _RING_SHAPES shapes in the
# first ring, each next ring _RING_GROWTH times farther.
_RING_SHAPES = 48
_RING_GROWTH = 3.0
_MAX_RINGS = 3


def trace_rings(parts: list[World], bound: np.ndarray, keep: np.ndarray, n_keep: int,
                 near: tuple[np.ndarray, ...], fan: Fan, best: np.ndarray,
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
            first, stop = rays.ranges(np.stack((phi - half, phi + half)), dist[cand] <= reach)
            ring[cand[stop == first]] = False
        if ring.any():
            Scene(parts, ring, ox, oy, scale, rng, subset=True).trace(fan, rays, best)



class Scene:
    """Admitted, in-range primitives for one cast from one origin.

    self.rows is the table of the front-facing admitted primitives, where RAD and VN of
    edges hold d and a.n, so that rows RAD: are exactly the per-edge terms of the pair
    test (d, a.n, nx, ny, dt_min, dt_max); self.ends the column where each kind ends."""

    def __init__(self, parts: list[World], keep: np.ndarray, ox: float, oy: float, scale: float,
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
                picked.append(World(part.rows.take(idx, axis=1), part.owner.take(idx), counts,
                                    part.bound, part.rounded))
            world = merge(picked)
            sel = np.ones(world.owner.shape[0], dtype=bool)
            others = list(world.counts[1:])
        elif len(parts) > 1:
            world = merge(parts)
            sel = keep[world.owner]
            others = None
        else:  # static geometry only (the common case): reuse per-filter work from earlier casts
            world = parts[0]
            _, base, sel, others, every_edge = _static_selection(world, keep)
        rows, n_e = world.rows, world.counts[0]
        # Tables from merge or take are this cast's own, so d and a.n can go straight into
        # them once read; the cached static table keeps a scratch copy for them instead.
        static = not subset and len(parts) == 1
        work = rows
        if static:
            assert world.scratch is not None  # made by _static_selection above
            work = world.scratch
        dan = work[RAD:VN + 1, :n_e] if static else np.empty((2, n_e))
        # Chipmunk's plane test for edges: d = a.n - v0.n - r; the edge is skipped if d < 0.
        an = np.multiply(rows[NX, :n_e], ox, out=dan[1])
        an += oy * rows[NY, :n_e]
        d = np.subtract(an, rows[VN, :n_e], out=dan[0])
        rad_e = None
        if world.rounded:  # r is 0.0 otherwise, and x - 0.0 is x
            d -= rows[RAD, :n_e]
            rad_e = rows[RAD, :n_e]
        if static:
            np.greater_equal(d, 0.0, out=sel[:n_e])
            if not every_edge:
                sel[:n_e] &= base[:n_e]
        else:
            sel[:n_e] &= d >= 0.0
        if others is None:
            bounds = list(itertools.accumulate(world.counts))
            others = [int(np.count_nonzero(sel[a:b])) for a, b in zip(bounds, bounds[1:])]
        if rad_e is not None:
            rad_e = rad_e.compress(sel[:n_e])  # before work's RAD row is overwritten
        if not static:
            work[RAD:VN + 1, :n_e] = dan
        self.rows = work.compress(sel, axis=1)  # much faster than rows[:, sel]
        self.ends = list(itertools.accumulate([int(np.count_nonzero(sel[:n_e]))] + others))
        self.n_edges = self.ends[0]
        self._intervals(self.rows[RAD, :self.n_edges], rad_e)

    def _intervals(self, d: np.ndarray, rad_e: np.ndarray | None) -> None:
        """Ray-angle interval lohi[0]..lohi[1] that can hit each primitive, or the full turn
        where full (None: nowhere); rad_e: the edges' radii if any is nonzero.

        Each primitive is a capsule A-B of radius r. A front-facing edge runs counter-
        clockwise from A (v0) to B (v_prev) as seen from the origin (cross(A-o, B-o) equals
        |edge| * d >= 0); segments are swapped into that order. The A..B arc is widened by
        the half-angle of the wider end disc (radius r + slack), which holds the capsule.
        Rounding moves Chipmunk's hit points by ~1e-15 * scale, far inside these margins.
        An interval wider than a turn needs no flag: it covers every ray (some twice)."""
        rows, ne = self.rows, self.n_edges
        nf_end, seg_start = self.ends[1], self.ends[2]
        rel = rows[:4] - np.array(((self.ox,), (self.oy,), (self.ox,), (self.oy,)))
        m = rel.shape[1]
        if seg_start < m:
            s = rel[:, seg_start:]
            flip = s[0] * s[3] - s[1] * s[2] < 0.0
            rel[:, seg_start:] = np.where(flip, s[[2, 3, 0, 1]], s)
        phi = np.arctan2(rel[1::2], rel[0::2])
        span = phi[1] - phi[0]
        np.add(span, TWO_PI, out=span, where=span < 0.0)
        # Origin near an edge's plane: its end points may be near too, and Chipmunk may
        # report t = 0 on any ray when the origin is on the plane; take the full turn.
        # (An origin near a flag is caught by the RayCaster's _side_flags.)
        # With d > 0 only den > 0 gives t >= 0, unless d / den underflows to -0.0, which
        # Chipmunk's t >= 0 test passes: keep that test when some d is (nearly) zero.
        self.on_plane = ne > 0 and float(d.min()) <= EDGE_NEAR * self.scale
        lohi = self.lohi = np.empty((2, m))
        # Sharp edges and flags: every end point is farther than EDGE_NEAR * scale, so a
        # fixed angular margin covers the rounding. Everything else gets the positional slack.
        start = 0 if rad_e is not None else nf_end
        if start == m:
            half: np.ndarray | float = self.margin
            full = None
            if self.on_plane:
                full = np.zeros(m, dtype=bool)
                np.less_equal(d, EDGE_NEAR * self.scale, out=full[:ne])
        else:
            full = np.zeros(m, dtype=bool)
            if self.on_plane:
                np.less_equal(d, EDGE_NEAR * self.scale, out=full[:ne])
            half = np.full(m, self.margin)
            radius = rows[RAD, start:] if rad_e is None else np.concatenate((rad_e, rows[RAD, ne:]))
            reach = radius + self.slack
            dist = np.hypot(rel[0::2, start:], rel[1::2, start:])
            near = np.minimum(dist[0], dist[1])
            half[start:] += np.arcsin(np.minimum(reach / near, 1.0))
            full[start:] |= near <= reach
            if seg_start < m:
                a, b = rel[:2, seg_start:], rel[2:, seg_start:]
                e = b - a
                u = np.clip(-(a * e).sum(axis=0) / ((e * e).sum(axis=0) + 1e-300), 0.0, 1.0)
                full[seg_start:] |= np.hypot(*(a + u * e)) - rows[RAD, seg_start:] <= self.slack
        np.subtract(phi[0], half, out=lohi[0])
        np.add(span, 2.0 * half, out=lohi[1])
        lohi[1] += lohi[0]
        self.full = full

    def trace(self, fan: Fan, rays: Rays, best: np.ndarray) -> None:
        """Lower best (alpha per ray) by every hit among the given rays."""
        if self.lohi.shape[1] == 0:
            return
        ray, counts, stop = rays.expand(*rays.ranges(self.lohi, self.full))
        ends = self.ends
        p = [0] + [int(stop[e - 1]) if e else 0 for e in ends]  # pair index where each kind ends
        bxy = fan.ends.take(ray, axis=1)
        rows = self.rows
        if p[1]:
            k = np.repeat(rows[RAD:, :ends[0]], counts[:ends[0]], axis=1)
            edge_pairs(k, ray[:p[1]], bxy[:, :p[1]], best, self.ox, self.oy, self.on_plane)
        if p[2] > p[1]:
            fan.flagged.append(ray[p[1]:p[2]])
        if p[3] > p[2]:
            k = np.repeat(rows[:RAD + 1, ends[1]:ends[2]], counts[ends[1]:ends[2]], axis=1)
            circle_pairs(k[AX], k[AY], k[RAD], ray[p[2]:p[3]], bxy[:, p[2]:p[3]], best, self.ox, self.oy)
        if p[4] > p[3]:
            k = np.repeat(rows[:NY + 1, ends[2]:], counts[ends[2]:], axis=1)
            segment_pairs(k, ray[p[3]:], bxy[:, p[3]:], best, self.ox, self.oy)



def _static_selection(world: World, keep: np.ndarray) -> tuple:
    """Per-filter work on the cached static table, kept on the table itself: (keep, the
    admitted columns, a buffer for this cast's selection whose non-edge part is already
    filled in, the admitted count of each non-edge kind, whether every edge is admitted)."""
    if world.scratch is None:
        world.scratch, world.selections = world.rows.copy(), {}
    found = world.selections.get(id(keep))
    if found is None or found[0] is not keep:
        base = keep[world.owner]
        bounds = list(itertools.accumulate(world.counts))
        others = [int(np.count_nonzero(base[a:b])) for a, b in zip(bounds, bounds[1:])]
        found = world.selections[id(keep)] = (keep, base, base.copy(), others,
                                              bool(base[:world.counts[0]].all()))
    return found
