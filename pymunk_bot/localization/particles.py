"""Operations on a particle set of poses (n, 3): resampling, KLD's bound, clusters, roughening."""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from pymunk_bot.localization.se2 import wrap

CLUSTER_BIN = 0.5  # [m] AMCL's cluster histogram (x, y)
MAX_CLUSTER_BINS = 4_000_000  # particles strewn farther than this many bins: no clustering
ROUGHENING = 1.0  # jitter after resampling, in spreads x n^(-1/3) (Gordon et al. 1993)


def kld_limit(k: np.ndarray, pf_err: float, pf_z: float) -> np.ndarray:
    """Particles needed for ``k`` occupied bins (Fox's bound; AMCL uses pf_z as z directly)."""
    k = np.maximum(np.asarray(k, dtype=float) - 1.0, 1e-12)
    b = 2.0 / (9.0 * k)
    return np.ceil(k / (2.0 * pf_err) * (1.0 - b + np.sqrt(b) * pf_z) ** 3)


def low_variance_indices(weights: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Systematic resampling: ``count`` indices, one random offset, evenly spaced pointers."""
    cumulative = np.cumsum(weights)
    cumulative /= cumulative[-1]
    pointers = (rng.random() + np.arange(count)) / count
    return np.minimum(np.searchsorted(cumulative, pointers), weights.size - 1)


def cluster_labels(poses: np.ndarray) -> np.ndarray | None:
    """Per pose, the label (1..) of its 8-connected cluster of CLUSTER_BIN (x, y) bins; None
    when the poses are strewn over more than MAX_CLUSTER_BINS bins."""
    xy = np.floor(poses[:, :2] / CLUSTER_BIN).astype(np.int64)
    lo = xy.min(axis=0)
    span = xy.max(axis=0) - lo + 1
    if span[0] * span[1] > MAX_CLUSTER_BINS:
        return None
    occupied = np.zeros(tuple(span), dtype=bool)
    cell = xy - lo
    occupied[cell[:, 0], cell[:, 1]] = True
    labels, _ = ndimage.label(occupied, structure=np.ones((3, 3)))
    return labels[cell[:, 0], cell[:, 1]]


def cluster_modes(poses: np.ndarray, weights: np.ndarray, labels: np.ndarray, least: float,
                  most: int) -> tuple[np.ndarray, np.ndarray]:
    """The weighted mean poses (k, 3) and shares of the belief (k,) of the heaviest clusters
    (``labels`` from :func:`cluster_labels`), at most ``most`` of them, each holding at least
    ``least`` of the weight; heaviest first."""
    mass = np.bincount(labels, weights=weights)
    share = mass / mass.sum()
    order = [int(k) for k in np.argsort(share)[::-1][:most] if share[k] >= least]
    means = [weighted_pose_stats(poses[labels == k], weights[labels == k])[0] for k in order]
    return np.reshape(means, (len(order), 3)), share[order]


def roughen(poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Jitter resampled poses by ``ROUGHENING * spread * n^(-1/3)`` per dimension (Gordon et
    al. 1993), the spread and n of each pose's own cluster: resampling copies particles, so
    without it a wide cloud (a global start, a kidnapping) keeps only its few lucky poses and
    cannot home in when the odometry noise (alpha1-4) is small; a converged cloud (cm spread)
    moves by mm, which changes nothing. (The spread of the whole set, when it holds candidates
    metres apart, jittered every one of them by decimetres and degrees: none could home in.)"""
    n = poses.shape[0]
    if n < 2:
        return poses
    labels = cluster_labels(poses)
    if labels is None:
        labels = np.zeros(n, dtype=np.intp)
    count = np.bincount(labels).astype(float)
    scale = np.zeros((count.size, 3))
    for dim, values in ((0, poses[:, 0]), (1, poses[:, 1])):
        mean = np.bincount(labels, values) / np.maximum(count, 1.0)
        var = np.bincount(labels, values * values) / np.maximum(count, 1.0) - mean * mean
        scale[:, dim] = np.sqrt(np.maximum(var, 0.0))
    cos = np.bincount(labels, np.cos(poses[:, 2])) / np.maximum(count, 1.0)
    sin = np.bincount(labels, np.sin(poses[:, 2])) / np.maximum(count, 1.0)
    # circular std [rad]; the resultant of equal headings can round to just above 1
    resultant = np.clip(np.hypot(cos, sin), 1e-12, 1.0)
    scale[:, 2] = np.minimum(np.sqrt(-2.0 * np.log(resultant)), np.pi)
    scale *= ROUGHENING * np.maximum(count, 1.0)[:, None] ** (-1.0 / 3.0)
    scale[count < 2] = 0.0
    out = poses + rng.normal(0.0, 1.0, poses.shape) * scale[labels]
    out[:, 2] = wrap(out[:, 2])
    return out


def weighted_pose_stats(poses: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean (circular for theta) and weighted sample covariance of poses (n, 3)."""
    w = weights / weights.sum()
    theta = np.arctan2(w @ np.sin(poses[:, 2]), w @ np.cos(poses[:, 2]))
    mean = np.array([w @ poses[:, 0], w @ poses[:, 1], theta])
    d = poses - mean
    d[:, 2] = wrap(d[:, 2])
    return mean, (d * w[:, None]).T @ d
