"""Point-to-line ICP (Censi's PLICP idea, Gauss-Newton form): align a scan with reference lines.

The reference is a submap of local line fits (:meth:`Reference.surfaces`): centroids and
normals of the neighbourhoods of the submap's end points. Each scan point is paired with the
nearest fit (scipy's cKDTree) within ``max_pair``; its error is its distance to that line,
n . (R p + t - q), weighed by Cauchy's kernel and by how well its neighbourhood is a line (a
corner or a curve fitted as one is a less certain line: :meth:`Reference.surfaces`); an
optional prior (the odometry) makes the match a maximum a posteriori one. Continuous
geometry: no grid, so no quantisation bias.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from pymunk_bot.localization.scanmatch import MIN_POINTS, Match
from pymunk_bot.localization.se2 import transform_points, wrap

POINT_CORRELATION = 3.0  # variance inflation for correlated neighbouring beams (as ekf's match_cov_scale)
MIN_POINT_STD = 0.002  # [m] floor of the per-point residual std
SURFACE_RADIUS = 0.2  # [m] neighbourhood of a reference point's line fit
SURFACE_MAX_RADIUS = 0.5  # [m] the widest it grows to where points are sparse
SURFACE_NEIGHBOURS = 32  # at most this many neighbours per fit (enough to fill SURFACE_RADIUS)
SURFACE_CELL = 0.04  # [m] the submap's points are thinned to one per cell of this size
SURFACE_MIN_POINTS = 5  # fewer neighbours within SURFACE_MAX_RADIUS: no fit
SURFACE_THINNESS = 0.4  # std across / std along the line at most this


class Reference:
    """World points with normals and weights, indexed for nearest-neighbour pairing."""

    def __init__(self, points: np.ndarray, normals: np.ndarray,
                 weights: np.ndarray | None = None) -> None:
        self.points, self.normals = points, normals
        # how much a scan point paired with each line counts (1: a line as thin as most)
        self.weights = np.ones(points.shape[0]) if weights is None else weights
        self.tree = cKDTree(points) if points.shape[0] else None

    @classmethod
    def surfaces(cls, points: np.ndarray, radius: float = SURFACE_RADIUS,
                 weighed: bool = True) -> "Reference":
        """Local line fits of a cloud (the end points of several scans, world frame): for each
        point, the centroid and normal of its neighbours within ``radius`` (at least
        SURFACE_MIN_POINTS, thin enough to be a line: clutter is left out). Fitted
        over every scan of the submap, the lines average the range noise out; a normal from a
        point's two neighbours in its own scan was tilted by about 6 deg at 5 m with 180 beams
        and 2.5 cm noise, and pairing with a raw noisy point added that point's noise.

        Each fit's weight is 2 s / (s + v): v its neighbours' variance across the line, s the
        median of v over the fits (most are stretches of wall: s is the cloud's noise). A
        stretch of wall weighs about 1, one seen through many scans up to 2, a corner or a
        rack's end taken for a line (v several times s) a few tenths. Weighed alike, such fits
        turned every match a little towards the scan's turn: a scan matched to the other
        scans at their *true* poses, no range noise, warehouse, came out 0.07 deg off a
        keyframe, 0.025 deg one way on average, 5 deg over a tour (now 0.005 deg off);
        docs/localization.md, "SLAM: lines that are not lines". ``weighed`` False: every fit 1."""
        empty = cls(np.empty((0, 2)), np.empty((0, 2)))
        if points.shape[0] < SURFACE_MIN_POINTS:
            return empty
        # One point per SURFACE_CELL (the centroid of those in it): overlapping scans would
        # otherwise pack a point's nearest neighbours into a few centimetres of wall.
        _, cell, per_cell = np.unique(np.floor(points / SURFACE_CELL).astype(np.int64), axis=0,
                                      return_inverse=True, return_counts=True)
        cell = cell.ravel()
        points = np.column_stack([np.bincount(cell, points[:, 0]), np.bincount(cell, points[:, 1])]) / per_cell[:, None]
        if points.shape[0] < SURFACE_MIN_POINTS:
            return empty
        # Where a sparse scan leaves fewer than SURFACE_MIN_POINTS within ``radius`` (one scan
        # of 180 beams has 17 cm between points at 5 m), the neighbourhood widens to hold
        # them, up to SURFACE_MAX_RADIUS: else the first keyframes had no surfaces to match.
        dist, idx = cKDTree(points).query(points, k=SURFACE_NEIGHBOURS,
                                          distance_upper_bound=max(radius, SURFACE_MAX_RADIUS))
        reach = np.maximum(radius, dist[:, SURFACE_MIN_POINTS - 1])  # inf: too few within max
        idx = np.where(dist <= reach[:, None], idx, points.shape[0])
        padded = np.vstack([points, np.full((1, 2), np.nan)])
        near = padded[idx]  # (n, k, 2); NaN where fewer than k neighbours
        count = np.count_nonzero(idx < points.shape[0], axis=1)
        centroid = np.nanmean(near, axis=1)
        centred = np.nan_to_num(near - centroid[:, None, :])
        cov = np.einsum("nki,nkj->nij", centred, centred) / np.maximum(count, 1)[:, None, None]
        values, vectors = np.linalg.eigh(cov)  # ascending: column 0 is the normal
        keep = (count >= SURFACE_MIN_POINTS) & (values[:, 0] <= SURFACE_THINNESS ** 2 * values[:, 1])
        if not keep.any():
            return empty
        if not weighed:
            return cls(centroid[keep], vectors[keep, :, 0])
        across = values[keep, 0]  # [m^2]
        typical = max(float(np.median(across)), MIN_POINT_STD ** 2)
        return cls(centroid[keep], vectors[keep, :, 0], 2.0 * typical / (typical + across))


def icp(reference: Reference, points: np.ndarray, guess: np.ndarray, iterations: int = 20,
        max_pair: float = 0.3, huber: float = 0.05, cov_scale: float = 1.0,
        prior: np.ndarray | None = None, start: np.ndarray | None = None) -> Match:
    """Align robot-frame ``points`` (m, 2) with ``reference``, from ``guess``. ``prior``: the
    information matrix (3x3, world frame) of ``guess`` as a measurement of the pose (odometry):
    the match is then the maximum a posteriori pose, which holds the directions the scan does
    not fix (a corridor's length) where the odometry puts them instead of letting them slide.
    ``start``: the pose the iterations start from, when not ``guess`` (the prior stays there)."""
    pose = np.array(guess if start is None else start, dtype=float)
    prior_info = np.zeros((3, 3)) if prior is None else np.asarray(prior, dtype=float)
    fail = Match(pose, np.eye(3) * 1e6, 0.0, float("inf"), False)
    if reference.tree is None or points.shape[0] < MIN_POINTS:
        return fail
    hessian = np.eye(3)
    pair_radius = max_pair
    for _ in range(iterations):
        world = transform_points(pose, points)
        dist, idx = reference.tree.query(world, distance_upper_bound=pair_radius)
        paired = np.isfinite(dist)
        if np.count_nonzero(paired) < MIN_POINTS:
            return fail
        p, q = points[paired], reference.points[idx[paired]]
        n = reference.normals[idx[paired]]
        w_pts = world[paired]
        r = np.einsum("ij,ij->i", n, w_pts - q)
        c, s = np.cos(pose[2]), np.sin(pose[2])
        dx = -s * p[:, 0] - c * p[:, 1]
        dy = c * p[:, 0] - s * p[:, 1]
        jac = np.column_stack([n[:, 0], n[:, 1], n[:, 0] * dx + n[:, 1] * dy])
        # Cauchy's kernel: a point paired with the wrong surface (a place the reference has not
        # seen yet, paired with the edge of what it has) pulls less the farther it is; Huber's
        # pulled with a constant force, always backwards for a robot driving into the unknown.
        w = reference.weights[idx[paired]] / (1.0 + (r / huber) ** 2)
        # Per-point variance: the robust spread of the residuals, inflated for the correlation
        # of neighbouring beams (POINT_CORRELATION), to weigh the scan against the prior.
        variance = POINT_CORRELATION * max((1.4826 * float(np.median(np.abs(r)))) ** 2, MIN_POINT_STD ** 2)
        hessian = (jac * w[:, None]).T @ jac / variance + prior_info
        offset = pose - np.asarray(guess, dtype=float)
        offset[2] = float(wrap(offset[2]))
        try:
            step = -np.linalg.solve(hessian + 1e-9 * np.eye(3),
                                    (jac * w[:, None]).T @ r / variance + prior_info @ offset)
        except np.linalg.LinAlgError:
            return fail
        pose += step
        pose[2] = float(wrap(pose[2]))
        pair_radius = max(0.5 * pair_radius, 4.0 * huber)  # tighten as it converges
        if np.hypot(step[0], step[1]) < 1e-6 and abs(step[2]) < 1e-6:
            break
    inlier = np.abs(r) <= huber
    m = int(np.count_nonzero(inlier))
    if m < MIN_POINTS or np.linalg.cond(hessian) > 1e8:
        return Match(pose, np.eye(3) * 1e6, m / points.shape[0], float("inf"), False)
    covariance = np.linalg.inv(hessian) * cov_scale
    return Match(pose, 0.5 * (covariance + covariance.T), m / points.shape[0],
                 float(np.sqrt(np.mean(r[inlier] ** 2))), True)
