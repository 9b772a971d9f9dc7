"""Many casts from many origins in one pass: the (origin, primitive, ray) triples of every
LiDAR due this tick go through the exact kernels together, so a fleet pays numpy's per-call
overhead once per tick instead of once per robot.

Exactness is the single cast's: the same kernels (Chipmunk's formulas, per triple), the same
end points (``reference.endpoints``), candidate intervals with the same margins. Every origin
for which the single cast would take a careful path (an origin on or near a shape, near a
static box's side line, on an edge's plane, rounded polygons) is handed to the single cast.
"""

from __future__ import annotations

import bisect
import math
from typing import Any, Sequence

import numpy as np
import pymunk

from pymunk_bot.sensors.raycast.fan import TWO_PI
from pymunk_bot.sensors.raycast.primitives import AX, AY, BX, BY, DTMAX, DTMIN, NX, NY, RAD, VN, World
from pymunk_bot.sensors.raycast.kernels import circle_pairs, edge_pairs, segment_pairs
from pymunk_bot.sensors.raycast.reference import check_args, endpoints
from pymunk_bot.sensors.raycast.scene import DENSE_SHAPES, EDGE_NEAR, _EDGE_MARGIN

_TURNS = np.array([-TWO_PI, 0.0, TWO_PI])
_SPACING = 8.0 * math.pi  # [rad] each origin's angles are shifted apart by this much


def cast_many(caster: Any, origins: Sequence[tuple[float, float]] | np.ndarray,
              angles: Sequence[np.ndarray] | np.ndarray, max_ranges: Sequence[float] | np.ndarray,
              filters: list[pymunk.ShapeFilter]) -> list[np.ndarray]:
    """Distances along every ray of every cast, as ``caster.cast`` gives them one by one
    (``caster``: the RayCaster, whose module calls this one)."""
    out: list[np.ndarray | None] = [None] * len(origins)
    # Casts grouped by the table they see (filters whose bodies rested may keep an older
    # one): per table, its bounding circles and (index, ox, oy, angles, max range, keep, filter).
    groups: dict[int, tuple[World, np.ndarray, list[tuple]]] = {}
    for i, (origin, ang, rng, f) in enumerate(zip(origins, angles, max_ranges, filters)):
        ox, oy, ang, rng = check_args(origin, ang, rng)
        parts, bound, keep, _ = caster.scene_cache.world(f)
        scale = 1.0 + abs(ox) + abs(oy) + rng
        usable = (len(parts) == 1 and not parts[0].rounded and ang.shape[0] > 0
                  and not _near_side_lines(caster, ox, oy, scale)
                  and caster.space.point_query_nearest((ox, oy), 1e-9 * scale, f) is None)
        if not usable:
            out[i] = caster.cast((ox, oy), ang, rng, f)
            continue
        groups.setdefault(id(parts[0]), (parts[0], bound, []))[2].append(
            (i, ox, oy, ang, rng, keep, f))
    for table, bounds, batch in groups.values():
        while batch:
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):  # as the kernels expect
                traced, careful = _trace(caster, table, bounds, batch)
            for i, ranges in traced.items():
                out[i] = ranges
            for k in careful:  # on an edge's plane, or crowded: the single cast's path
                i, ox, oy, ang, rng, _, f = batch[k]
                out[i] = caster.cast((ox, oy), ang, rng, f)
            batch = [b for k, b in enumerate(batch) if k not in careful] if careful else []
    return [r if r is not None else np.empty(0) for r in out]


def _near_side_lines(caster: Any, ox: float, oy: float, scale: float) -> bool:
    """Within EDGE_NEAR * scale of a static bounding box's side line (see the caster's side flags, RayCaster _side_flags)."""
    near = EDGE_NEAR * scale
    for sides, v in ((caster.scene_cache.side_x, ox), (caster.scene_cache.side_y, oy)):
        i = bisect.bisect_left(sides, v - near)
        if i < len(sides) and sides[i] <= v + near:
            return True
    return False


def _trace(caster: Any, table: World, bounds: np.ndarray,
           batch: list[tuple]) -> tuple[dict[int, np.ndarray], set[int]]:
    """Ranges by cast index; or, if some origins lie on an edge's plane or see crowds (more
    shapes in range than the single cast traces without rings), nothing traced and those
    origins (batch positions) to cast singly."""
    k_count = len(batch)
    index = [b[0] for b in batch]
    ox = np.array([b[1] for b in batch])
    oy = np.array([b[2] for b in batch])
    rng = np.array([b[4] for b in batch])
    scale = 1.0 + np.abs(ox) + np.abs(oy) + rng
    slack = 1e-9 * scale
    n_rays = np.array([b[3].shape[0] for b in batch])
    ray_start = np.concatenate(([0], np.cumsum(n_rays)[:-1]))
    ends_list, theta_list, ray3_list = [], [], []
    for k, (_, x, y, ang, r, _, _) in enumerate(batch):
        cos, sin, ends = endpoints(x, y, ang, r)
        ends_list.append(ends)
        theta = np.arctan2(sin, cos)
        order = np.argsort(theta, kind="stable")
        theta_list.append(((theta[order] + _TURNS[:, None]).ravel()) + k * _SPACING)
        order += ray_start[k]
        ray3_list.append(np.concatenate((order, order, order)))
    ends = np.concatenate(ends_list, axis=1)
    theta_all = np.concatenate(theta_list)
    ray3_all = np.concatenate(ray3_list)
    best = np.ones(int(n_rays.sum()))

    # Which primitives each origin can see: admitted by its filter and within its range.
    keep = np.stack([b[5] for b in batch])  # (K, shapes)
    dx = bounds[0][None, :] - ox[:, None]
    dy = bounds[1][None, :] - oy[:, None]
    gap = np.sqrt(dx * dx + dy * dy) - bounds[2][None, :]
    seen = keep & (gap <= (rng + slack)[:, None])
    crowded = np.flatnonzero(seen.sum(axis=1) > DENSE_SHAPES)
    if crowded.shape[0]:  # the single cast culls occluded shapes in rings: cheaper there
        return {}, set(crowded.tolist())
    k_idx, p_idx = np.nonzero(seen[:, table.owner])
    rows = table.rows
    counts = np.cumsum(table.counts)  # kind boundaries: edges | flags | circles | segments
    kind = np.searchsorted(counts, p_idx, side="right")

    # Edges: Chipmunk's plane test from each origin (d = a.n - v0.n), front-facing only.
    e = kind == 0
    ek, ep = k_idx[e], p_idx[e]
    an = rows[NX, ep] * ox[ek]
    an += oy[ek] * rows[NY, ep]
    d = an - rows[VN, ep]
    on_plane = np.abs(d) <= EDGE_NEAR * scale[ek]
    if on_plane.any():
        return {}, set(np.unique(ek[on_plane]).tolist())
    front = d >= 0.0
    ek, ep, d, an = ek[front], ep[front], d[front], an[front]
    o = ~e
    ok_, op = k_idx[o], p_idx[o]
    pk = np.concatenate((ek, ok_))
    pp = np.concatenate((ep, op))
    n_e = ek.shape[0]

    # The ray-angle interval each (origin, primitive) can be hit in (see the scene's _intervals).
    relx_a = rows[AX, pp] - ox[pk]
    rely_a = rows[AY, pp] - oy[pk]
    relx_b = rows[BX, pp] - ox[pk]
    rely_b = rows[BY, pp] - oy[pk]
    pkind = kind[np.concatenate((np.flatnonzero(e)[front], np.flatnonzero(o)))]
    seg = pkind == 3
    if seg.any():
        flip = seg & (relx_a * rely_b - rely_a * relx_b < 0.0)
        relx_a[flip], relx_b[flip] = relx_b[flip], relx_a[flip].copy()
        rely_a[flip], rely_b[flip] = rely_b[flip], rely_a[flip].copy()
    phi_a = np.arctan2(rely_a, relx_a)
    span = np.arctan2(rely_b, relx_b) - phi_a
    np.add(span, TWO_PI, out=span, where=span < 0.0)
    margin = _EDGE_MARGIN + 1e-15 * scale[pk] / rng[pk]
    half = margin.copy()
    full = np.zeros(pk.shape[0], dtype=bool)
    round_ = pkind >= 2  # circles and segments: widen by the end discs
    if round_.any():
        radius = rows[RAD, pp[round_]]
        reach = radius + slack[pk[round_]]
        near_end = np.minimum(np.hypot(relx_a[round_], rely_a[round_]),
                              np.hypot(relx_b[round_], rely_b[round_]))
        half[round_] += np.arcsin(np.minimum(reach / near_end, 1.0))
        full[round_] |= near_end <= reach
        if seg.any():
            ax_, ay_, bx_, by_ = relx_a[seg], rely_a[seg], relx_b[seg], rely_b[seg]
            ex, ey = bx_ - ax_, by_ - ay_
            u = np.clip(-(ax_ * ex + ay_ * ey) / ((ex * ex + ey * ey) + 1e-300), 0.0, 1.0)
            closest = np.hypot(ax_ + u * ex, ay_ + u * ey) - rows[RAD, pp[seg]]
            full[seg] |= closest <= slack[pk[seg]]
    lo = phi_a - half + pk * _SPACING
    hi = lo + span + 2.0 * half
    first = np.searchsorted(theta_all, lo, "left")
    stop = np.searchsorted(theta_all, hi, "right")
    # A full interval covers every ray of its origin once: the middle turn of its tiling.
    base = 3 * ray_start[pk]
    first = np.where(full, base + n_rays[pk], first)
    stop = np.where(full, base + 2 * n_rays[pk], stop)
    width = stop - first
    pair_end = np.cumsum(width)
    entry = np.repeat(stop - pair_end, width) + np.arange(int(pair_end[-1]) if pair_end.shape[0] else 0)
    ray = ray3_all[entry]
    owner = np.repeat(np.arange(pk.shape[0]), width)
    tk = pk[owner]
    tp = pp[owner]
    tox, toy = ox[tk], oy[tk]
    bxy = ends[:, ray]
    m = int(pair_end[n_e - 1]) if n_e else 0  # edge pairs come first: their triples lead
    if m:
        # The per-pair edge terms, gathered once per pair and then taken per triple.
        edge_terms = np.stack((d, an, rows[NX, ep], rows[NY, ep], rows[DTMIN, ep], rows[DTMAX, ep]))
        edge_pairs(edge_terms.take(owner[:m], axis=1), ray[:m], bxy[:, :m], best, tox[:m],
                   toy[:m], False)
    tkind = pkind[owner]
    flagged = ray[tkind == 1]
    circ = tkind == 2
    if circ.any():
        cx, cy, r = rows[[AX, AY, RAD]].take(pp, axis=1).take(owner[circ], axis=1)
        circle_pairs(cx, cy, r, ray[circ], bxy[:, circ], best, tox[circ], toy[circ])
    segs = tkind == 3
    if segs.any():
        q = tp[segs]
        segment_pairs(rows[:NY + 1, q], ray[segs], bxy[:, segs], best, tox[segs], toy[segs])
    for r in np.unique(flagged).tolist():  # past a box corner lying on its shape: ask pymunk
        k = int(np.searchsorted(ray_start, r, "right") - 1)
        start, end = (float(ox[k]), float(oy[k])), (float(ends[0, r]), float(ends[1, r]))
        hit = caster.space.segment_query_first(start, end, 0.0, batch[k][6])
        best[r] = 1.0 if hit is None else hit.alpha
    result = {}
    for k in range(k_count):
        s = ray_start[k]
        result[index[k]] = best[s:s + n_rays[k]] * rng[k]
    return result, set()
