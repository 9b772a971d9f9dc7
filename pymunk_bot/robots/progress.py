"""The per-tick bookkeeping after the physics: path length and goals reached (compiled, over
the fleet's rows), and what feeds each drive's encoders to its odometry.

Passes over the robots' new positions instead of six numpy calls (a stack of 16 copies
paid ~10 us a tick for them). The arithmetic is the arrays' to the bit: dx * dx + dy * dy
(a sum of two is the same float either way round), IEEE sqrt, no fused multiply-adds.
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numba
import numpy as np


@numba.njit(cache=True)
def travel_rows(xy: np.ndarray, last: np.ndarray, distance: np.ndarray) -> None:
    """Add each robot's step from ``last`` to ``xy`` (n, 2) [m] to ``distance`` [m] and copy
    ``xy`` into ``last`` (the fleet's positions change in place: copies' views stay live)."""
    for i in range(xy.shape[0]):
        travel_to(i, xy[i, 0], xy[i, 1], last, distance)


@numba.njit(cache=True)
def travel_to(i: int, x: float, y: float, last: np.ndarray, distance: np.ndarray) -> None:
    """Robot ``i`` moved from ``last[i]`` to (x, y) [m]: the step added to ``distance[i]`` [m],
    (x, y) kept in ``last[i]``."""
    dx = x - last[i, 0]
    dy = y - last[i, 1]
    distance[i] += math.sqrt(dx * dx + dy * dy)
    last[i, 0], last[i, 1] = x, y


@numba.njit(cache=True)
def reach_goals(xy: np.ndarray, distance: np.ndarray, pending: np.ndarray, goal: np.ndarray,
                tolerance2: np.ndarray, time: np.ndarray, time_to_goal: np.ndarray,
                distance_to_goal: np.ndarray, reached: np.ndarray) -> int:
    """Of the ``pending`` robots (their goals (p, 2) [m] and squared tolerances [m^2] in that
    order), those at ``xy`` (n, 2) [m] now within tolerance get ``time`` [s] (each robot's, or
    one for all: shape (1,)) and their path length so far (``distance`` [m]), and are flagged
    in ``reached`` (p,). Returns how many were reached."""
    one_time = time.shape[0] != xy.shape[0]
    count = 0
    for j in range(pending.shape[0]):
        i = pending[j]
        dx = xy[i, 0] - goal[j, 0]
        dy = xy[i, 1] - goal[j, 1]
        hit = dx * dx + dy * dy <= tolerance2[j]
        reached[j] = hit
        if hit:
            time_to_goal[i] = time[0] if one_time else time[i]
            distance_to_goal[i] = distance[i]
            count += 1
    return count


def odometry_feed(drive: Any, odometry: Any) -> Callable[[], None]:
    """What integrates ``drive``'s encoder input into ``odometry`` after each tick: the
    odometry's ``take`` of the drive's ``travel`` (zeroed in the same call) where both have
    them (the built-in diff drive's), else ``update(drive.take_travel())``."""
    if hasattr(odometry, "take") and isinstance(getattr(drive, "travel", None), np.ndarray):
        return lambda: odometry.take(drive.travel)  # read each time: a stack rebinds it
    return lambda: odometry.update(drive.take_travel())
