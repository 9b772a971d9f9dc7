"""Turning a grid path into an any-angle path, and polyline helpers."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from pymunk_bot.planning.grid import ClearanceGrid

Point = tuple[float, float]


def path_length(path: Sequence[Point]) -> float:
    """Length of a polyline [m]."""
    return sum(math.dist(a, b) for a, b in zip(path, path[1:]))


def _corners(path: Sequence[Point]) -> list[int]:
    """Indices where a grid path changes direction (plus both ends)."""
    keep = [0]
    for k in range(1, len(path) - 1):
        (x0, y0), (x1, y1), (x2, y2) = path[k - 1], path[k], path[k + 1]
        if abs((x1 - x0) * (y2 - y1) - (y1 - y0) * (x2 - x1)) > 1e-12:
            keep.append(k)
    keep.append(len(path) - 1)
    return keep


def shortcut(grid: ClearanceGrid, path: Sequence[Point], wanted: float) -> list[Point]:
    """Greedy line-of-sight smoothing ("string pulling") of a grid path.

    From each kept point, jump to the farthest later corner that a straight segment reaches with
    a clearance of at least ``min(wanted, clearance of the grid path in between)``: the result is
    shorter and straighter, yet never passes closer to an obstacle than ``wanted`` unless the
    grid path itself had to (in a doorway).
    """
    points: list[Point] = [(p[0], p[1]) for p in path]
    if len(points) <= 2:
        return points
    xy = np.asarray(points)
    along = grid.clearance[grid.cells_of(xy[:, 0], xy[:, 1])]
    corners = _corners(points)
    # Sampling a slanted segment reads cells the grid path did not use; allow for that.
    slack = 0.25 * grid.resolution
    out = [points[0]]
    i = 0
    while i < len(points) - 1:
        floors = np.minimum.accumulate(along[i:])
        candidates = [k for k in corners if k > i]
        # Greedy: extend the straight segment corner by corner while it stays clear enough.
        best = candidates[0]
        for k in candidates[1:]:
            need = min(wanted, float(floors[k - i])) - slack
            if grid.segment_clearance(points[i], points[k]) < need:
                break
            best = k
        i = best
        out.append(points[i])
    return out


def densify(path: Sequence[Point], spacing: float) -> list[Point]:
    """The same polyline with extra points so no segment is longer than ``spacing`` [m]."""
    if len(path) < 2:
        return list(path)
    out: list[Point] = [(path[0][0], path[0][1])]
    for a, b in zip(path, path[1:]):
        n = max(1, math.ceil(math.dist(a, b) / spacing))
        for k in range(1, n + 1):
            t = k / n
            out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])))
    return out
