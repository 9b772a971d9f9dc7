"""The metrics' formulas, as plain functions of arrays (each written once, tested by hand)."""
from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, inline="always")
def disc_clearance(dx: float, dy: float, robot_radius: float, human_radius: float) -> float:
    """Clearance [m] between a disc robot and a human disc, (dx, dy) [m] apart: |d| - r_r -
    r_h (negative while they overlap)."""
    return math.hypot(dx, dy) - robot_radius - human_radius


@numba.njit(cache=True, nogil=True)
def disc_clearances(robot_xy: np.ndarray, robot_radius: float, human_xy: np.ndarray,
                    human_radius: np.ndarray) -> np.ndarray:
    """:func:`disc_clearance` [m] to each human: ``human_xy`` (n, 2), ``human_radius`` (n,)."""
    out = np.empty(len(human_xy))
    for i in range(len(human_xy)):
        out[i] = disc_clearance(human_xy[i, 0] - robot_xy[0], human_xy[i, 1] - robot_xy[1],
                                robot_radius, human_radius[i])
    return out


@numba.njit(cache=True, nogil=True)
def time_to_collision(dx: float, dy: float, wx: float, wy: float, reach: float) -> float:
    """Constant-velocity time to contact [s]: the smallest t >= 0 with |d + w t| = R, d the
    human's position relative to the robot [m], w its relative velocity [m/s], R the sum of
    their radii [m]. 0 while already within R; inf when the two never come within R (moving
    apart, or missing each other)."""
    c = dx * dx + dy * dy - reach * reach
    if c <= 0.0:
        return 0.0
    a = wx * wx + wy * wy
    b = 2.0 * (dx * wx + dy * wy)
    disc = b * b - 4.0 * a * c
    if b < 0.0 and disc >= 0.0 and a > 0.0:
        return (-b - math.sqrt(disc)) / (2.0 * a)
    return math.inf


@numba.njit(cache=True, nogil=True)
def times_to_collision(rel_xy: np.ndarray, rel_v: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """:func:`time_to_collision` [s] of each human (rows of ``rel_xy``, ``rel_v``, ``reach``)."""
    out = np.empty(len(rel_xy))
    for i in range(len(rel_xy)):
        out[i] = time_to_collision(rel_xy[i, 0], rel_xy[i, 1], rel_v[i, 0], rel_v[i, 1],
                                   reach[i])
    return out


@numba.njit(cache=True, nogil=True)
def encounters(human_xy: np.ndarray, human_v: np.ndarray, human_radius: np.ndarray,
               rx: float, ry: float, rvx: float, rvy: float, robot_radius: float,
               clear: np.ndarray, disc: bool, personal: float,
               inside: np.ndarray) -> tuple[float, int, bool, float]:
    """One instant of the human metrics of a robot at (``rx``, ``ry``) [m] moving at (``rvx``,
    ``rvy``) [m/s], of bounding radius ``robot_radius`` [m], among humans (``human_xy``,
    ``human_v``, ``human_radius``): each one's clearance [m] into ``clear`` (a ``disc``
    robot's, :func:`disc_clearance`; else ``clear`` holds them already), then (the least
    clearance [m], how many humans entered the ``personal`` space [m] since the last instant
    (``inside``, updated in place), whether any is in it, the least :func:`time_to_collision`
    [s])."""
    closest, entries, any_inside, least = math.inf, 0, False, math.inf
    for i in range(len(clear)):
        dx, dy = human_xy[i, 0] - rx, human_xy[i, 1] - ry
        if disc:
            clear[i] = disc_clearance(dx, dy, robot_radius, human_radius[i])
        closest = min(closest, clear[i])
        now = clear[i] < personal
        entries += int(now and not inside[i])
        any_inside = any_inside or now
        inside[i] = now
        least = min(least, time_to_collision(dx, dy, human_v[i, 0] - rvx, human_v[i, 1] - rvy,
                                             robot_radius + human_radius[i]))
    return closest, entries, any_inside, least


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
