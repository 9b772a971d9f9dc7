"""Scan-to-map matching: the pose that puts a scan's end points on a map's obstacles.

Gauss-Newton on the likelihood field (Kohlbrecher et al.'s Hector SLAM idea, with exact
distances): minimise sum_i rho(d(T(pose) p_i)) where d is the distance to the nearest obstacle
and rho is Huber's loss (residuals past ``huber`` count linearly, so clutter and unmapped
objects pull less). End points whose distance is saturated at the field's cap carry no
gradient and are left out. The covariance is the Gauss-Newton one, s^2 (J^T W J)^-1 with the
residual variance s^2 estimated from the fit, times ``cov_scale``: neighbouring beams hit the
same stretch of wall through the same map cells, so their errors are correlated and the
textbook covariance (which assumes independent beams) is too small; tests/localization
measures the factor that makes it honest.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.localization.se2 import transform_points, wrap

MIN_POINTS = 10  # fewer matched end points than this: no match


@dataclass(frozen=True)
class Match:
    """A scan match: the pose, its covariance, and how well the scan fits."""

    pose: np.ndarray  # [x, y, theta]
    covariance: np.ndarray  # 3x3
    inliers: float  # fraction of end points within ``huber`` of an obstacle
    rmse: float  # [m] of the inlier residuals
    ok: bool  # enough points and a well-conditioned fit


def subsample(points: np.ndarray, max_points: int) -> np.ndarray:
    """At most ``max_points`` of ``points``, evenly spread over the scan."""
    if points.shape[0] <= max_points:
        return points
    return points[np.linspace(0, points.shape[0] - 1, max_points).round().astype(np.intp)]


def match_scan(field: LikelihoodField, points: np.ndarray, guess: np.ndarray, iterations: int = 10,
               huber: float = 0.1, cov_scale: float = 1.0) -> Match:
    """Gauss-Newton from ``guess``: align robot-frame ``points`` (m, 2) with ``field``."""
    pose = np.array(guess, dtype=float)
    fail = Match(pose, np.eye(3) * 1e6, 0.0, float("inf"), False)
    if points.shape[0] < MIN_POINTS:
        return fail
    px, py = points[:, 0], points[:, 1]
    hessian = np.eye(3)
    for _ in range(iterations):
        world = transform_points(pose, points)
        d, g = field.distance_and_gradient(world)
        c, s = np.cos(pose[2]), np.sin(pose[2])
        jac = np.column_stack([g[:, 0], g[:, 1],
                               g[:, 0] * (-s * px - c * py) + g[:, 1] * (c * px - s * py)])
        use = d < 0.999 * field.max_dist
        w = np.where(use, np.where(d <= huber, 1.0, huber / np.maximum(d, 1e-12)), 0.0)
        if np.count_nonzero(use) < MIN_POINTS:
            return fail
        hessian = (jac * w[:, None]).T @ jac
        gradient = (jac * w[:, None]).T @ d
        try:
            step = -np.linalg.solve(hessian + 1e-9 * np.eye(3), gradient)
        except np.linalg.LinAlgError:
            return fail
        pose = pose + step
        pose[2] = float(wrap(pose[2]))
        if np.hypot(step[0], step[1]) < 1e-5 and abs(step[2]) < 1e-5:
            break
    world = transform_points(pose, points)
    d, _ = field.distance_and_gradient(world)
    inlier = d <= huber
    n = int(np.count_nonzero(inlier))
    if n < MIN_POINTS or np.linalg.cond(hessian) > 1e8:
        return Match(pose, np.eye(3) * 1e6, n / points.shape[0], float("inf"), False)
    rmse = float(np.sqrt(np.mean(d[inlier] ** 2)))
    variance = max(float(np.sum(d[inlier] ** 2)) / max(n - 3, 1), (0.25 * field.resolution) ** 2)
    covariance = variance * np.linalg.inv(hessian) * cov_scale
    return Match(pose, 0.5 * (covariance + covariance.T), n / points.shape[0], rmse, True)
