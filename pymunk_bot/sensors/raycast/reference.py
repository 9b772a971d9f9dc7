"""Argument checks, segment end points shared by both casters, and the ground truth.

``reference_cast`` is one ``segment_query_first`` per ray. ``RayCaster`` falls back to it
(or to single queries) wherever rounding could make its own answer differ, so it must
build exactly the same segments: both take their end points from ``endpoints``.
"""

from __future__ import annotations

import math

from typing import TYPE_CHECKING

import numpy as np
import pymunk

if TYPE_CHECKING:
    from pymunk_bot.sensors.raycast.spaces import Spaces


def check_args(origin: tuple[float, float], angles: np.ndarray,
               max_range: float) -> tuple[float, float, np.ndarray, float]:
    """Validated (ox, oy, angles as float64, max_range)."""
    ox, oy = float(origin[0]), float(origin[1])
    ang = np.asarray(angles, dtype=np.float64)
    if ang.ndim != 1:
        raise ValueError(f"angles must be a 1-D array, got shape {ang.shape}")
    rng = float(max_range)
    if not (math.isfinite(rng) and rng > 0.0):
        raise ValueError(f"max_range must be positive and finite, got {max_range!r}")
    if not (math.isfinite(ox) and math.isfinite(oy)) or not bool(np.isfinite(ang).all()):
        raise ValueError("origin and angles must be finite")
    return ox, oy, ang, rng


def endpoints(ox: float, oy: float, ang: np.ndarray,
              rng: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """cos, sin and the (2, n) segment end points origin + rng * (cos, sin); shared so both
    casters query identical segments."""
    ends = np.empty((2, ang.shape[0]))
    cos, sin = np.cos(ang, out=ends[0]), np.sin(ang, out=ends[1])
    ends = ends * rng  # a new array: cos and sin stay intact
    ends += np.array(((ox,), (oy,)))
    return cos, sin, ends


def endpoints_many(ox: np.ndarray, oy: np.ndarray, ang: np.ndarray,
                   rng: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`endpoints` of K casts at once (origins and ranges (K,), angles (K, n)): cos and
    sin (K, n) and end points (K, 2, n), each row the very floats :func:`endpoints` gives."""
    trig = np.empty((2,) + ang.shape)
    cos, sin = np.cos(ang, out=trig[0]), np.sin(ang, out=trig[1])
    ends = np.empty((ang.shape[0], 2, ang.shape[1]))
    np.multiply(cos, rng[:, None], out=ends[:, 0])
    np.multiply(sin, rng[:, None], out=ends[:, 1])
    ends[:, 0] += ox[:, None]
    ends[:, 1] += oy[:, None]
    return cos, sin, ends


def reference_cast(space: "pymunk.Space | Spaces", origin: tuple[float, float],
                   angles: np.ndarray, max_range: float,
                   shape_filter: pymunk.ShapeFilter = pymunk.ShapeFilter()) -> np.ndarray:
    """The ground truth: one ``segment_query_first`` per ray; ``alpha * max_range`` or ``max_range``."""
    ox, oy, ang, rng = check_args(origin, angles, max_range)
    _, _, ends = endpoints(ox, oy, ang, rng)
    out = np.full(ang.shape[0], rng)
    query, start = space.segment_query_first, (ox, oy)
    for i, end in enumerate(zip(*ends.tolist())):
        hit = query(start, end, 0.0, shape_filter)
        if hit is not None:
            out[i] = hit.alpha * rng
    return out
