"""Whether a loop closure candidate is one: the new scan aligned with an old keyframe's submap.

A closure is one measurement that the graph then trusts for good, so it is accepted only when
the match says where the robot is, and nowhere else:

- **it fits**: at least ``min_inliers`` of the scan's points on the submap;
- **it is pinned down**: position std at most LOOP_MAX_STD along the match's worst axis and
  heading std at most LOOP_MAX_HEADING_STD (a corridor's length is not);
- **it is consistent**: the correction it makes to the estimate is one the chain's accumulated
  covariance explains (chi^2_3 <= LOOP_CONSISTENCY);
- **it is unique**: started again AMBIGUITY_STEP, 2x and 3x that either way along its worst
  axis, the ICP finds no other pose more than AMBIGUITY_DISTANCE away that fits as well (its
  inliers within AMBIGUITY_INLIERS of the match's). A warehouse aisle's racks repeat: a scan
  fitted two places 40 cm apart along the aisle alike, the ICP from the estimate took the wrong
  one with a stated std of 4.9 cm, and the accepted closure put the map 40 cm off (warehouse,
  uncalibrated, revisiting, seed 18, once the front end's heading held better;
  docs/localization-journal.md, "SLAM: a heading held over 10 m, and closures that are unique").

Every line fit counts alike here (``weighed=False`` references): in an aisle the racks' ends
are what pins a match along it, and a closure is one measurement, so the small turn they give
it does not add up as the front end's chain does.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.localization.icp import Reference, icp
from pymunk_bot.localization.scanmatch import Match
from pymunk_bot.localization.se2 import wrap

LOOP_GATE = 3.0  # [std] how far the accumulated uncertainty widens the candidate search
LOOP_MAX_PAIR = 1.0  # [m] the loop match's first pairing radius, at most
LOOP_MAX_STD = 0.05  # [m] a closure's match: largest position std at most
LOOP_MAX_HEADING_STD = math.radians(1.0)  # [rad] its heading std at most
LOOP_CONSISTENCY = 16.27  # chi^2_3 (99.9 %) of the correction against the accumulated covariance
AMBIGUITY_STEP = 0.2  # [m] the uniqueness test's restarts: this far apart along the worst axis
AMBIGUITY_STEPS = 3  # ... this many either way (0.6 m: the spacing of a rack's uprights and more)
AMBIGUITY_DISTANCE = 0.1  # [m] a restart that ends farther than this from the match is another pose
AMBIGUITY_INLIERS = 0.05  # ... and fits as well when its inlier share is within this of the match's


def verify_closure(reference: Reference, points: np.ndarray, estimate: np.ndarray,
                   accumulated: np.ndarray, floor: np.ndarray, *, iterations: int, max_pair: float,
                   huber: float, min_inliers: float, sensor: np.ndarray) -> Match | None:
    """The match of the new keyframe's ``points`` (robot frame [m]) with an old keyframe's
    submap ``reference`` (unweighed line fits, world frame), from its ``estimate`` [x, y,
    theta], if it verifies a closure (module docstring); else None. ``accumulated``: the 3x3
    covariance of the new keyframe relative to the old one; ``floor``: what every edge's
    covariance gets added; ``sensor``: the LiDAR's position in the robot frame [m]."""
    reach = LOOP_GATE * math.sqrt(max(float(np.linalg.eigvalsh(accumulated[:2, :2])[-1]), 0.0))
    match = icp(reference, points, estimate, iterations, min(max(max_pair, reach), LOOP_MAX_PAIR),
                huber, sensor=sensor)
    if not (match.ok and match.inliers >= min_inliers):
        return None
    cov = match.covariance
    if (float(np.linalg.eigvalsh(cov[:2, :2])[-1]) > LOOP_MAX_STD ** 2
            or float(cov[2, 2]) > LOOP_MAX_HEADING_STD ** 2):
        return None  # a corridor's length, or too few surfaces: not pinned down
    correction = match.pose - estimate
    correction[2] = float(wrap(correction[2]))
    chi2 = float(correction @ np.linalg.solve(accumulated + cov + floor, correction))
    if chi2 > LOOP_CONSISTENCY:
        return None
    if ambiguous(reference, points, match, iterations=iterations, max_pair=max_pair, huber=huber,
                 sensor=sensor):
        return None
    return match


def ambiguous(reference: Reference, points: np.ndarray, match: Match, *, iterations: int,
              max_pair: float, huber: float, sensor: np.ndarray) -> bool:
    """Whether another pose fits ``points`` as well as ``match`` does: the ICP restarted
    AMBIGUITY_STEP apart along the match's worst position axis, AMBIGUITY_STEPS either way,
    ends more than AMBIGUITY_DISTANCE from it with an inlier share within AMBIGUITY_INLIERS."""
    _, axes = np.linalg.eigh(match.covariance[:2, :2])
    worst = axes[:, -1]  # [unit] the direction the match is least sure of
    for k in range(1, AMBIGUITY_STEPS + 1):
        for sign in (1.0, -1.0):
            start = np.array(match.pose, dtype=float)
            start[:2] += sign * k * AMBIGUITY_STEP * worst
            other = icp(reference, points, start, iterations, max_pair, huber, sensor=sensor)
            if (other.ok and other.inliers >= match.inliers - AMBIGUITY_INLIERS
                    and float(np.hypot(*(other.pose[:2] - match.pose[:2]))) > AMBIGUITY_DISTANCE):
                return True
    return False
