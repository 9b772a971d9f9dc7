"""Planar rigid transforms on [x, y, theta] arrays, vectorised over leading axes.

``compose(a, b)`` is a (+) b: pose ``b`` expressed in frame ``a``, taken to the world frame.
``between(a, b)`` is a^-1 (+) b: pose ``b`` seen from frame ``a`` (the relative motion a -> b).
"""
from __future__ import annotations

import numpy as np


def wrap(angle):
    """Angles wrapped to [-pi, pi) [rad]."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a (+) b for poses of shape (..., 3); theta is wrapped."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([a[..., 0] + c * b[..., 0] - s * b[..., 1],
                     a[..., 1] + s * b[..., 0] + c * b[..., 1],
                     wrap(a[..., 2] + b[..., 2])], axis=-1)


def between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a^-1 (+) b for poses of shape (..., 3): the motion from ``a`` to ``b`` in ``a``'s frame."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap(b[..., 2] - a[..., 2])], axis=-1)


def transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (m, 2) in the frame of each pose (..., 3) -> world points (..., m, 2)."""
    pose = np.asarray(pose, dtype=float)
    c, s = np.cos(pose[..., 2])[..., None], np.sin(pose[..., 2])[..., None]
    px, py = points[:, 0], points[:, 1]
    return np.stack([pose[..., 0, None] + c * px - s * py,
                     pose[..., 1, None] + s * px + c * py], axis=-1)


def scan_points(scan, keep_max_range: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Beam end points of a LaserScan in the robot frame (m, 2) and which beams they are.

    Beams without a return (reading max_range or below min_range) are left out unless
    ``keep_max_range``; the mount offset (x, y) is added (the angles already carry its yaw).
    """
    ranges = np.asarray(scan.ranges, dtype=float)
    angles = np.asarray(scan.angles, dtype=float)
    keep = np.isfinite(ranges) & (ranges >= scan.min_range)
    if not keep_max_range:
        keep &= ranges < scan.max_range
    index = np.flatnonzero(keep)
    r, a = ranges[index], angles[index]
    ox, oy = scan.offset[0], scan.offset[1]
    return np.stack([ox + r * np.cos(a), oy + r * np.sin(a)], axis=-1), index
