"""Poses that explain a scan, found on the map without a prior: the proposal a lost particle
filter draws from (sensor resetting, Lenser & Veloso 2000; the dual proposal of Mixture MCL,
Thrun et al. 2001).

A particle filter can only settle where it has particles. A global start or a kidnapping
spreads ``max_particles`` over the whole free space; in a 1000 m^2 warehouse that is about one
particle per 2 m^2 at a random heading, so none is within 0.3 m and 10 deg of the robot (it
was so in every failed run instrumented) and the cloud settles on whichever look-alike place it
happens to cover. :func:`search` draws many poses uniformly where the robot fits, scores each
with a few beams, polishes the best ones by Gauss-Newton on the distance field (the same
alignment the EKF does, vectorised over poses) and scores them again with the scan's used beams.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.localization.se2 import transform_points, wrap

SEARCH_DRAWS = 20_000  # uniform poses scored per search (bounds its cost: ~0.5 M lookups)
SEARCH_BEAMS = 24  # beams that score the draws
SEARCH_KEEP = 64  # best draws polished and returned
REFINE_ITERATIONS = 8  # Gauss-Newton steps per polished pose
REFINE_HUBER = 0.1  # [m] residuals beyond this count linearly while polishing
MAX_STEP = (0.3, 0.3, 0.2)  # [m, m, rad] largest Gauss-Newton step (a damped, trusted region)
CHUNK_ENDPOINTS = 1_000_000  # end points looked up at once (bounds temporary memory)


def beam_log_pz(field: LikelihoodField, poses: np.ndarray, points: np.ndarray, sigma_hit: float,
                z_hit: float, z_rand_density: float) -> np.ndarray:
    """Per pose (n, 3), the mean over ``points`` (m, 2, robot frame) of log pz, the likelihood
    field's per-beam model ``pz = z_hit exp(-d^2 / 2 sigma_hit^2) + z_rand / max_range``."""
    out = np.empty(poses.shape[0])
    if points.shape[0] == 0:
        out[:] = np.log(z_hit + z_rand_density)
        return out
    chunk = max(1, CHUNK_ENDPOINTS // points.shape[0])
    denom = 2.0 * sigma_hit ** 2
    for start in range(0, poses.shape[0], chunk):
        d = field.distance(transform_points(poses[start:start + chunk], points))
        out[start:start + chunk] = np.log(z_hit * np.exp(-d * d / denom) + z_rand_density).mean(axis=1)
    return out


def refine(field: LikelihoodField, poses: np.ndarray, points: np.ndarray,
           iterations: int = REFINE_ITERATIONS, huber: float = REFINE_HUBER) -> np.ndarray:
    """Gauss-Newton alignment of ``points`` (m, 2) with the map from each of ``poses`` (k, 3) at
    once (robust Huber weights, end points at the field's cap left out, steps bounded)."""
    pose = np.array(poses, dtype=float)
    if pose.shape[0] == 0 or points.shape[0] < 3:
        return pose
    px, py = points[:, 0], points[:, 1]
    limit = np.asarray(MAX_STEP)
    for _ in range(iterations):
        world = transform_points(pose, points)  # (k, m, 2)
        d, g = field.distance_and_gradient(world.reshape(-1, 2))
        d, g = d.reshape(world.shape[:2]), g.reshape(world.shape)
        c, s = np.cos(pose[:, 2:3]), np.sin(pose[:, 2:3])
        jac = np.stack([g[..., 0], g[..., 1],
                        g[..., 0] * (-s * px - c * py) + g[..., 1] * (c * px - s * py)], axis=-1)
        use = d < 0.999 * field.max_dist
        w = np.where(use, np.where(d <= huber, 1.0, huber / np.maximum(d, 1e-12)), 0.0)
        hessian = np.einsum("kmi,km,kmj->kij", jac, w, jac) + 1e-6 * np.eye(3)
        gradient = np.einsum("kmi,km,km->ki", jac, w, d)
        step = -np.linalg.solve(hessian, gradient[..., None])[..., 0]
        step = np.clip(step, -limit, limit)
        pose += step
        pose[:, 2] = wrap(pose[:, 2])
        if np.all(np.abs(step) < 1e-5):
            break
    return pose


def search(field: LikelihoodField, points: np.ndarray, places: np.ndarray, rng: np.random.Generator,
           sigma_hit: float, z_hit: float, z_rand_density: float,
           draws: int = SEARCH_DRAWS, keep: int = SEARCH_KEEP) -> tuple[np.ndarray, np.ndarray]:
    """The ``keep`` poses (k, 3) that explain the scan's end ``points`` (m, 2, robot frame) best
    among ``draws`` drawn uniformly over ``places`` (n, 2: cell centres where the robot fits,
    cell size ``field.grid.resolution``), polished (:func:`refine`), and their mean log pz over
    all of ``points``, best first."""
    if places.shape[0] == 0 or points.shape[0] < 3:
        return np.empty((0, 3)), np.empty(0)
    cell = field.grid.resolution
    xy = places[rng.integers(0, places.shape[0], draws)] + rng.uniform(-0.5 * cell, 0.5 * cell, (draws, 2))
    poses = np.column_stack([xy, rng.uniform(-np.pi, np.pi, draws)])
    few = points[np.linspace(0, points.shape[0] - 1, min(SEARCH_BEAMS, points.shape[0])).round().astype(np.intp)]
    coarse = beam_log_pz(field, poses, few, sigma_hit, z_hit, z_rand_density)
    best = poses[np.argsort(coarse)[::-1][:keep]]
    polished = refine(field, best, points)
    score = beam_log_pz(field, polished, points, sigma_hit, z_hit, z_rand_density)
    order = np.argsort(score)[::-1]
    return polished[order], score[order]
