"""Point-to-line ICP (Censi's PLICP idea, Gauss-Newton form): align a scan with reference points.

Reference points carry normals, estimated from their neighbours along the scan that made them
(consecutive beam ends closer than ``max_gap``); each scan point is paired with the nearest
reference point (scipy's cKDTree) within ``max_pair`` and the error is its distance to that
point's line, n . (R p + t - q). Continuous geometry: no grid, so no quantisation bias.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .scanmatch import MIN_POINTS, Match
from .se2 import transform_points, wrap


def scan_normals(points: np.ndarray, beams: np.ndarray, max_gap: float = 0.3) -> tuple[np.ndarray, np.ndarray]:
    """Points that have a neighbour on both sides along the scan, and their unit normals."""
    if points.shape[0] < 3:
        return np.empty((0, 2)), np.empty((0, 2))
    prev, nxt = points[:-2], points[2:]
    mid = points[1:-1]
    ok = (np.diff(beams)[:-1] == 1) & (np.diff(beams)[1:] == 1)
    ok &= (np.hypot(*(mid - prev).T) < max_gap) & (np.hypot(*(nxt - mid).T) < max_gap)
    tangent = nxt - prev
    length = np.hypot(*tangent.T)
    ok &= length > 1e-9
    tangent = tangent[ok] / length[ok, None]
    return mid[ok], np.stack([-tangent[:, 1], tangent[:, 0]], axis=-1)


class Reference:
    """World points with normals, indexed for nearest-neighbour pairing."""

    def __init__(self, points: np.ndarray, normals: np.ndarray) -> None:
        self.points, self.normals = points, normals
        self.tree = cKDTree(points) if points.shape[0] else None


def icp(reference: Reference, points: np.ndarray, guess: np.ndarray, iterations: int = 20,
        max_pair: float = 0.3, huber: float = 0.05, cov_scale: float = 1.0) -> Match:
    """Align robot-frame ``points`` (m, 2) with ``reference``, from ``guess``."""
    pose = np.array(guess, dtype=float)
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
        w = np.where(np.abs(r) <= huber, 1.0, huber / np.maximum(np.abs(r), 1e-12))
        hessian = (jac * w[:, None]).T @ jac
        try:
            step = -np.linalg.solve(hessian + 1e-9 * np.eye(3), (jac * w[:, None]).T @ r)
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
    variance = float(np.sum(r[inlier] ** 2)) / max(m - 3, 1)
    covariance = max(variance, 1e-8) * np.linalg.inv(hessian) * cov_scale
    return Match(pose, 0.5 * (covariance + covariance.T), m / points.shape[0],
                 float(np.sqrt(np.mean(r[inlier] ** 2))), True)
