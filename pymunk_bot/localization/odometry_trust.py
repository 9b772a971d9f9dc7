"""How far SLAM's front end trusts the odometry: a prior that learns the robot it runs on.

Each keyframe's scan match is a maximum a posteriori one, with the odometry step as its prior
(icp.py): the prior holds the directions the scan does not fix, such as a corridor's length.
How wide that prior should be depends on the robot. A prior sized for an uncalibrated robot
(a few per cent of each step) let a well-calibrated robot's estimate random-walk along the
aisles of a warehouse at the scan's own noise, several times the odometry's; a prior sized for
a calibrated one held an uncalibrated robot to its wrong wheel radii.

So the prior keeps the shape of an uncalibrated robot's error model (a share of the step,
a random walk per metre and per radian: the EKF's defaults, docs/localization.md), and its
translation is fitted to the robot: wherever the scan alone pins a direction of the step down
(its variance there at most ``ACCEPT`` times the built-in prior's), the scan-only step minus
the odometry step samples the odometry's error there. The scan-only step is read off the
match itself: its information less the prior's. Over the last ``WINDOW`` keyframes, a least
squares fit of the forward samples against the distance driven gives the share of its travel
the odometry misses (wheel radii off), which corrects the prediction; the spread of what is
left, forward and sideways, scales the translation variance within [``SCALE_FLOOR``,
``SCALE_CEILING``] of the built-in model's. The spread includes the scan's own noise, so the
prior is never narrower than what the matches can show. The heading keeps the built-in
prior: its error is mostly a bias (wheels of unequal radii), and a narrower prior let that
bias into every keyframe, where the chain of keyframes adds it up.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from pymunk_bot.localization.se2 import compose, wrap

# An uncalibrated robot's odometry error over one step (the EKF's defaults): a systematic share
# of the motion (wheel radii, track width) and a random walk per metre driven and per radian.
ODOMETRY_SCALE_ERROR = 0.03  # fraction of the step
ODOMETRY_TRANS_NOISE = 0.03  # [m/sqrt(m)]
ODOMETRY_ROT_NOISE = 0.1  # [rad/sqrt(m)]
ODOMETRY_TURN_NOISE = 0.1  # [rad/sqrt(rad)]

ACCEPT = 0.25  # a direction is sampled when the scan's variance there is at most this share
# of the built-in prior's
WINDOW = 60  # [keyframes] samples kept
MIN_SAMPLES = 8  # fewer: the built-in prior
MAX_SCALE_CORRECTION = 0.2  # the learned correction of the travel odometry reports, at most
SCALE_FLOOR = 1e-4  # the learned variance scale's range (1e-4: a prior 100 times narrower)
SCALE_CEILING = 10.0
_MEDIAN_OF_CHI2_1 = 0.4549  # median of the square of a unit normal variable


def step_variances(step: np.ndarray) -> tuple[float, float]:
    """The built-in model's variance of an odometry ``step`` (robot frame: dx, dy [m],
    dtheta [rad]): translation [m^2] (each axis) and rotation [rad^2]."""
    d, a = float(np.hypot(step[0], step[1])), abs(float(step[2]))
    trans = (ODOMETRY_SCALE_ERROR * d) ** 2 + ODOMETRY_TRANS_NOISE ** 2 * d + 1e-8
    rot = ((ODOMETRY_SCALE_ERROR * a) ** 2 + ODOMETRY_ROT_NOISE ** 2 * d
           + ODOMETRY_TURN_NOISE ** 2 * a + 1e-8)
    return trans, rot


def _axes(heading: float) -> np.ndarray:
    """Rows: the robot's forward, left and turn directions in the world frame's pose space."""
    c, s = np.cos(heading), np.sin(heading)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def scan_only(pose: np.ndarray, covariance: np.ndarray, predicted: np.ndarray,
              prior: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """What the scan alone said of a maximum a posteriori match: ``pose`` [x, y, theta] with
    ``covariance`` (3x3, world frame), found with ``prior`` (its information matrix) about
    ``predicted``. Returns the scan-only pose's offset from ``predicted`` [m, m, rad] and its
    covariance (the match's information less the prior's), or None when that is singular."""
    offset = np.asarray(pose, dtype=float) - np.asarray(predicted, dtype=float)
    offset[2] = float(wrap(offset[2]))
    try:  # the scan-only pose x_s: H_s (x_s - g) = (H_s + P) (x - g), H_s = H - P
        scan_covariance = np.linalg.inv(np.linalg.inv(covariance) - prior + 1e-12 * np.eye(3))
    except np.linalg.LinAlgError:
        return None
    return offset + scan_covariance @ (prior @ offset), scan_covariance


class OdometryTrust:
    """The front end's odometry prior, learned from the matches so far (module docstring)."""

    def __init__(self) -> None:
        # Where the scan pinned the step's forward direction: the odometry's forward travel [m]
        # and the scan-only forward travel less it [m]; where it pinned the sideways one: that
        # difference [m]. Each with the built-in model's translation variance of its step.
        self._forward: deque[tuple[float, float, float]] = deque(maxlen=WINDOW)
        self._sideways: deque[tuple[float, float]] = deque(maxlen=WINDOW)
        self.travel_correction = 0.0  # the share of its forward travel the odometry misses
        self.variance_scale = 1.0  # of the built-in translation variance

    def predict(self, last: np.ndarray, step: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pose the odometry ``step`` (robot frame) from keyframe pose ``last`` predicts,
        its travel corrected, and that prediction's information matrix (3x3, world frame)."""
        corrected = np.array([step[0] * (1.0 + self.travel_correction), step[1], step[2]])
        predicted = compose(last, corrected)
        trans, rot = step_variances(step)
        trans *= self.variance_scale
        axes = _axes(float(predicted[2]))
        return predicted, axes.T @ np.diag([1.0 / trans, 1.0 / trans, 1.0 / rot]) @ axes

    def learn(self, step: np.ndarray, predicted: np.ndarray, pose: np.ndarray,
              covariance: np.ndarray, prior: np.ndarray) -> None:
        """Sample the odometry's error from a match: ``pose`` with ``covariance`` (3x3, world
        frame), found with ``prior`` (its information) about ``predicted`` by ``step``."""
        scan = scan_only(pose, covariance, predicted, prior)
        if scan is None:
            return
        scan_offset, scan_covariance = scan
        base = step_variances(step)[0]
        forward, sideways, _ = _axes(float(predicted[2]))
        if 0.0 <= float(forward @ scan_covariance @ forward) <= ACCEPT * base:
            driven = float(step[0])  # the odometry's forward travel [m]
            self._forward.append((driven, float(forward @ scan_offset)
                                  + self.travel_correction * driven, base))
        if 0.0 <= float(sideways @ scan_covariance @ sideways) <= ACCEPT * base:
            self._sideways.append((float(sideways @ scan_offset), base))
        if len(self._forward) + len(self._sideways) >= MIN_SAMPLES:
            self._fit()

    def _fit(self) -> None:
        """The travel correction and the variance scale from the samples kept."""
        forward = np.array(self._forward).reshape(-1, 3)
        travel, missed, forward_base = forward.T
        if travel.size >= MIN_SAMPLES:  # least squares: missed = correction * travel
            correction = float(travel @ missed) / max(float(travel @ travel), 1e-12)
            self.travel_correction = min(max(correction, -MAX_SCALE_CORRECTION),
                                         MAX_SCALE_CORRECTION)
        side, side_base = np.array(self._sideways).reshape(-1, 2).T
        ratios = np.concatenate([(missed - self.travel_correction * travel) ** 2 / forward_base,
                                 side ** 2 / side_base])
        spread = float(np.median(ratios)) / _MEDIAN_OF_CHI2_1
        self.variance_scale = min(max(spread, SCALE_FLOOR), SCALE_CEILING)
