"""The metrics' formulas, as plain functions of arrays (each written once, tested by hand)."""
from __future__ import annotations

import math

import numpy as np


def disc_clearances(robot_xy: np.ndarray, robot_radius: float, human_xy: np.ndarray,
                    human_radius: np.ndarray) -> np.ndarray:
    """Clearance [m] between a disc robot and each human disc: |p_h - p_r| - r_r - r_h
    (negative while they overlap). ``human_xy`` (n, 2), ``human_radius`` (n,)."""
    d = human_xy - robot_xy
    return np.hypot(d[:, 0], d[:, 1]) - robot_radius - human_radius


def times_to_collision(rel_xy: np.ndarray, rel_v: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Constant-velocity time to contact [s] for each human: the smallest t >= 0 with
    |d + w t| = R, d the human's position relative to the robot [m], w its relative
    velocity [m/s], R the sum of their radii [m]. 0 while already within R; inf when the two
    never come within R (moving apart, or missing each other)."""
    a = (rel_v ** 2).sum(axis=1)
    b = 2.0 * (rel_xy * rel_v).sum(axis=1)
    c = (rel_xy ** 2).sum(axis=1) - reach ** 2
    disc = b * b - 4.0 * a * c
    out = np.full(len(c), math.inf)
    course = (b < 0.0) & (disc >= 0.0) & (a > 0.0)
    out[course] = (-b[course] - np.sqrt(disc[course])) / (2.0 * a[course])
    out[c <= 0.0] = 0.0
    return out


def sample_kinematics(velocities: np.ndarray, period: float) -> dict[str, float]:
    """Speed [m/s], acceleration [m/s^2] and jerk [m/s^3] (min/mean/max) from velocity
    vectors sampled every ``period`` [s], shape (k, 2): a_k = |v_k - v_(k-1)| / period as a
    vector difference, jerk likewise from the acceleration vectors. NaN where there are too
    few samples."""
    v = np.asarray(velocities, dtype=float).reshape(-1, 2)
    speed = np.hypot(v[:, 0], v[:, 1])
    accel = np.diff(v, axis=0) / period
    jerk = np.diff(accel, axis=0) / period
    out: dict[str, float] = {}
    for name, values in (("speed", speed), ("acceleration", np.hypot(*accel.T)),
                         ("jerk", np.hypot(*jerk.T))):
        has = values.size > 0
        if name != "speed":  # mean_speed is path length / time (see mean_speed)
            out[f"mean_{name}"] = float(values.mean()) if has else math.nan
        out[f"min_{name}"] = float(values.min()) if has else math.nan
        out[f"max_{name}"] = float(values.max()) if has else math.nan
    return out


def failed_to_progress(times: np.ndarray, best: np.ndarray, window: float,
                       distance: float) -> bool:
    """Whether the closest approach to the goal so far, ``best`` [m] sampled at ``times``
    [s] (non-increasing, only samples before the goal), ever gained less than ``distance`` [m]
    over a whole ``window`` [s]."""
    times, best = np.asarray(times, dtype=float), np.asarray(best, dtype=float)
    if times.size == 0 or times[-1] - times[0] < window - 1e-9:
        return False
    # For each sample, the last sample at least a window earlier.
    earlier = np.searchsorted(times, times - window + 1e-9, side="right") - 1
    ok = earlier >= 0
    gained = best[earlier[ok]] - best[ok]
    return bool((gained < distance).any())


def mean_speed(path_length: float, elapsed: float) -> float:
    """Path length / time [m/s] (0 for a run of no time)."""
    return path_length / elapsed if elapsed > 0 else 0.0


def spl(success: bool, shortest: float, path_length: float) -> float:
    """Success weighted by path length (Anderson et al. 2018): S * L* / max(L*, L)."""
    if not success:
        return 0.0
    if not math.isfinite(shortest):
        return math.nan
    longest = max(shortest, path_length)
    return 1.0 if longest <= 0 else shortest / longest
