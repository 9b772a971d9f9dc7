"""The exact per-pair tests: Chipmunk's segment-query formulas, one (primitive, ray) pair
per array column, each lowering ``best`` (the alpha per ray) where it hits.

Every expression keeps Chipmunk's operand order, because reordering would change the
rounding and so, rarely, the answer: these are the only places where alphas are made.
"""

from __future__ import annotations

import numpy as np

# Chipmunk skips a polygon plane when |a.n - b.n| is below this literal (written 10e-6 in C).
_PARALLEL_EPS = 10e-6


def edge_pairs(k: np.ndarray, ray: np.ndarray, bxy: np.ndarray, best: np.ndarray,
               ox: float, oy: float, on_plane: bool) -> None:
    """cpPolyShapeSegmentQuery's plane test. k holds per-pair rows d, a.n, nx, ny, dt_min,
    dt_max (see scene.Scene); bxy the pair's segment end point. on_plane: some origin is
    (nearly) on an edge's plane, so keep Chipmunk's t >= 0 test (see scene.Scene)."""
    d, an, nx, ny, dt_min, dt_max = k
    bx, by = bxy
    den = an - (bx * nx + by * ny)
    t = d / den
    # Chipmunk also rejects t > 1; here such a t cannot lower best (which starts at 1).
    ok = ((np.abs(den) >= _PARALLEL_EPS) & (t >= 0.0)) if on_plane else den >= _PARALLEL_EPS
    one_t = 1.0 - t
    dt = nx * (oy * one_t + by * t) - ny * (ox * one_t + bx * t)
    ok &= (dt_min <= dt) & (dt <= dt_max)
    np.minimum.at(best, ray.compress(ok), t.compress(ok))


def circle_pairs(cx: np.ndarray, cy: np.ndarray, r: np.ndarray, ray: np.ndarray, bxy: np.ndarray,
                 best: np.ndarray, ox: float, oy: float) -> None:
    """Chipmunk's CircleSegmentQuery with query radius 0."""
    t, ok = circle_alpha(ox - cx, oy - cy, bxy[0] - cx, bxy[1] - cy, r)
    np.minimum.at(best, ray.compress(ok), t.compress(ok))


def segment_pairs(k: np.ndarray, ray: np.ndarray, bxy: np.ndarray, best: np.ndarray,
                  ox: float, oy: float) -> None:
    """cpSegmentShapeSegmentQuery with query radius 0, including the rounded end caps.
    k holds per-pair rows ax, ay, bx, by, r, (unused), nx, ny; ox, oy are floats, or arrays
    with one origin per pair."""
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
        if isinstance(ox, np.ndarray) and isinstance(oy, np.ndarray):  # one origin per pair
            ox, oy = ox[c], oy[c]
        t1, ok1 = circle_alpha(ox - tax[c], oy - tay[c], bx[c] - tax[c], by[c] - tay[c], r[c])
        t2, ok2 = circle_alpha(ox - tbx[c], oy - tby[c], bx[c] - tbx[c], by[c] - tby[c], r[c])
        # Chipmunk keeps cap 1 only if its alpha (1.0 when missed) is strictly smaller.
        a1, a2 = np.where(ok1, t1, 1.0), np.where(ok2, t2, 1.0)
        use1 = a1 < a2
        hit = np.where(use1, ok1, ok2)
        np.minimum.at(best, ray[c[hit]], np.where(use1, a1, a2)[hit])


def circle_alpha(dax: np.ndarray, day: np.ndarray, dbx: np.ndarray, dby: np.ndarray,
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
