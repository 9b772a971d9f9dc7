"""Returns short of the map: a LiDAR beam that stops clearly before the map's surface along it.

People, carts and opened doors are not on the map. A beam that hits one ends in the open, in
front of the wall the map has along it; MCL's likelihood field then reads a large distance
there (little harm) or, near another surface, pulls particles sideways to put the leg on it,
and the scan matcher's least squares do the same. AMCL's beam model handles it per particle
with ``z_short`` (an exponential density of returns shorter than expected, rate
``lambda_short``) and ``z_rand``; the likelihood field has no expected range to compare with.

Here the test is done once per scan, from one pose (the tracked estimate): each beam's expected
range is traced on the map's distance field (sphere tracing, explore.trace); a beam whose
measured range is shorter than that by more than ``margin`` is *short* and left out of the
weighting (MCL) or the match (EKF's scan matcher), and of MCL's scan fit (excused_fit). A
return longer than expected is kept: no moving thing explains it, so it is evidence that the
pose is wrong. A tracked estimate is within
centimetres, far inside ``margin``; from a wrong pose (a global start, a kidnapping) the test
would hide the very beams that contradict it, so MCL applies it only while localized.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.localization.explore import trace
from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.localization.se2 import transform_points

TRACE_TOLERANCE = 0.05  # [m] expected ranges are traced to within this (at most margin / 2)


def short_returns(field: LikelihoodField, pose: np.ndarray, points: np.ndarray,
                  mount: tuple[float, float], max_range: float, margin: float) -> np.ndarray:
    """Boolean (m,): which robot-frame end ``points`` (m, 2) of beams from the sensor at
    ``mount`` (x, y, robot frame) end more than ``margin`` [m] short of the map's surface seen
    from ``pose`` [x, y, theta] along the same beam (traced up to ``max_range`` [m])."""
    points = np.asarray(points, dtype=float)
    if points.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    rel = points - np.asarray(mount, dtype=float)[None, :]
    measured = np.hypot(rel[:, 0], rel[:, 1])
    origin = transform_points(np.asarray(pose, dtype=float), np.asarray([mount], dtype=float))
    heading = float(pose[2]) + np.arctan2(rel[:, 1], rel[:, 0])
    tolerance = max(min(TRACE_TOLERANCE, 0.5 * margin), 0.5 * field.resolution)
    expected = trace(field, origin, heading[None, :], max_range, tolerance)[0]
    return measured < expected - margin


def excused_fit(fits: np.ndarray, short: np.ndarray, min_usable: int) -> float | None:
    """The share of returns that fit the map (``fits``, boolean per return) among those not
    ``short``; None (the scan neither confirms nor contradicts the pose) when fewer than
    ``min_usable`` returns are not short.

    However many are short, they are not held against the pose: a robot wedged among people
    has most beams on them (measured: 70-90 % of the used returns, all on walkers, the
    estimate within 5 cm). A wrong pose is told by the returns that are not short: they end
    at or beyond the map's surface along their beam, and beyond it they miss. (Until
    2026-12-05 short returns past 60 % of the scan counted as misfits, which made a robot
    among people give up a right pose.) A wrong pose from which nearly every return is short
    (a hall on the map where the robot is in a small closed room) goes unnoticed until a
    return that is not short shows up.
    """
    usable = ~np.asarray(short, dtype=bool)
    kept = int(np.count_nonzero(usable))
    if kept < min_usable:
        return None
    return int(np.count_nonzero(np.asarray(fits, dtype=bool) & usable)) / kept
