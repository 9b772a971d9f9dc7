"""Rays that may run along a static bounding box's side line: their directions, per origin.

A ray along a side line starts (within rounding) on the line and points along it; pymunk's
box test is then decided by rounding (see cache.corner_flags), so such rays are flagged and
pymunk answers them. The tolerances are generous because flagged rays are exact anyway, only
slower.
"""
from __future__ import annotations

import bisect
import math
from typing import Any

import numpy as np

from pymunk_bot.sensors.raycast.scene import EDGE_NEAR

# Rays within this angle [rad] of a box side line through the origin are left to pymunk.
SIDE_ANGLE = 1e-4
FEW_ORIGINS = 32  # up to this many casts, side lines are looked up origin by origin
_ALONG_X = (-0.5 * math.pi, 0.5 * math.pi)  # [rad] along a vertical side line
_ALONG_Y = (-math.pi, 0.0, math.pi)  # [rad] along a horizontal one


def side_lohi(directions: list[float]) -> np.ndarray:
    """(2, k) angle intervals [rad] around side-line directions."""
    return np.array(([a - SIDE_ANGLE for a in directions], [a + SIDE_ANGLE for a in directions]))


def side_directions(cache: Any, ox: float, oy: float, scale: float) -> list[float] | None:
    """Directions [rad] of the rays from (ox, oy) that may run along a side line of the
    cache's static bounding boxes; None if the origin is within EDGE_NEAR * scale of both a
    vertical and a horizontal side line (so perhaps of a flag), where no ray can be trusted
    to the fast path."""
    near, corner = 1e-7 * scale, EDGE_NEAR * scale
    directions: list[float] = []
    close = 0
    for lines, v, along in ((cache.side_x, ox, _ALONG_X), (cache.side_y, oy, _ALONG_Y)):
        i = bisect.bisect_left(lines, v - corner)
        if i < len(lines) and lines[i] <= v + corner:
            close += 1
            i = bisect.bisect_left(lines, v - near)
            if i < len(lines) and lines[i] <= v + near:
                directions.extend(along)
    return None if close == 2 else directions


def sides_many(cache: Any, ox: np.ndarray, oy: np.ndarray, scale: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`side_directions` for many origins: side intervals (K, 2, 5) [rad], how many each
    has, and which origins are near a vertical and a horizontal side line at once."""
    k = ox.shape[0]
    sides = np.zeros((k, 2, 5))
    n_sides = np.zeros(k, dtype=np.intp)
    if k <= FEW_ORIGINS:  # numpy's per-call cost dominates: the single cast's rule
        cornered = np.zeros(k, dtype=np.bool_)
        for row, (x, y, c) in enumerate(zip(ox.tolist(), oy.tolist(), scale.tolist())):
            directions = side_directions(cache, x, y, c)
            if directions is None:
                cornered[row] = True
            elif directions:
                sides[row, :, :len(directions)] = side_lohi(directions)
                n_sides[row] = len(directions)
        return sides, n_sides, cornered
    near, corner = 1e-7 * scale, EDGE_NEAR * scale
    found = []
    for lines, v in zip(cache.side_lines, (ox, oy)):
        i = np.searchsorted(lines, v - corner)
        close = i < lines.shape[0]
        close[close] &= lines[i[close]] <= (v + corner)[close]
        i = np.searchsorted(lines, v - near)
        on = i < lines.shape[0]
        on[on] &= lines[i[on]] <= (v + near)[on]
        found.append((close, on & close))
    (close_x, on_x), (close_y, on_y) = found
    for row in np.flatnonzero(on_x | on_y).tolist():
        directions = (list(_ALONG_X) if on_x[row] else []) + (list(_ALONG_Y) if on_y[row] else [])
        sides[row, :, :len(directions)] = side_lohi(directions)
        n_sides[row] = len(directions)
    return sides, n_sides, close_x & close_y
