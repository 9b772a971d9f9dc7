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
weighting (MCL) or the match (EKF's scan matcher). A return longer than expected is kept: no
moving thing explains it, so it is evidence that the pose is wrong. A tracked estimate is within
centimetres, far inside ``margin``; from a wrong pose (a global start, a kidnapping) the test
would hide the very beams that contradict it, so MCL applies it only while localized.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.localization.explore import trace
from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.localization.se2 import transform_points

# At most this share of a scan's returns is excused as short: past it, the map and the scan
# disagree too much for people alone to explain (a wrong pose seeing a small room as a hall),
# and the excess counts against the fit (see excused_fit).
MAX_SHORT_SHARE = 0.6
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


def excused_fit(fits: np.ndarray, short: np.ndarray) -> float:
    """The share of returns that fit the map (``fits``, boolean per return) among those not
    ``short``; short ones beyond MAX_SHORT_SHARE of the scan count as misfits. 1.0 with none."""
    total = fits.size
    if total == 0:
        return 1.0
    kept = total - int(np.count_nonzero(short))
    hits = int(np.count_nonzero(fits & ~short))
    return hits / max(kept, (1.0 - MAX_SHORT_SHARE) * total)
