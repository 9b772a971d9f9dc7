"""EKF localization against the map: odometry predicts, a scan-to-map match corrects.

State: the pose [x, y, theta] and its 3x3 covariance P.

- **Predict** (every tick): the odometry motion since the last tick, ``u = odom_prev^-1 odom``,
  is applied to the estimate, ``x <- x (+) u``, and P <- F P F^T + G Q G^T with Q (in the robot
  frame) growing with the distance and angle moved: ``trans_noise^2 * d`` along and across,
  ``rot_noise^2 * d + turn_noise^2 * |dtheta|`` in heading. Encoder noise is a random walk in
  travelled distance, so variance grows with distance, not time.
- **Update** (on each fresh scan): Gauss-Newton scan matching from the predicted pose gives a
  measured pose z with covariance R (scanmatch.py, inflated by ``match_cov_scale``, plus
  ``map_std^2`` in x and y for a map whose walls are off by that much); the
  measurement model is z = x + noise (H = I). An innovation beyond the Mahalanobis ``gate``
  is refused (a bad match), and the Joseph form keeps P symmetric and positive.
- **Systematic odometry error.** An uncalibrated robot's wheel radii and track width are off
  by a few percent: its odometry errs by a *fraction* of each motion, the same sign every time,
  which white noise growing with sqrt(distance) cannot cover. Before each correction, P gains
  the error that fraction (``calibration_error``) makes over the motion since the last
  correction: ``c * D`` along and across the track, ``c * A + c * D / track`` in heading (a
  wheel off by c turns the robot by c * D / track). Between corrections a bias is white, so this
  is honest without knowing the simulator's true drift.
- **No lock-out.** ``gate_patience`` good matches in a row refused by the gate mean the filter,
  not the scans, is wrong (its noise model was too optimistic): P is widened by the squared
  innovation and the match is folded in, so the filter recovers instead of coasting on
  odometry forever.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.localization.config import EkfConfig
from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.localization.dynamic import short_returns
from pymunk_bot.localization.scanmatch import MIN_POINTS, match_scan, subsample
from pymunk_bot.localization.se2 import between, compose, scan_points, wrap

MIN_TRACK = 0.1  # [m] the lever for heading drift when the robot has no wheel track (omni)


class EkfLocalizer(Localizer):
    """Extended Kalman filter localization with scan-to-map matching as the measurement."""

    needs_map = True
    needs_lidar = True

    def __init__(self, config: EkfConfig, context: LocalizerContext) -> None:
        super().__init__(config, context)
        if context.map is None:
            raise ValueError("ekf needs a map (the scenario's, or world.map)")
        self.field = LikelihoodField(context.map, config.max_dist)
        self.covariance = np.diag(np.square(config.initial_std))
        self._odom: np.ndarray | None = None
        self.updates = 0  # scans folded in
        self.rejected = 0  # matches refused by the gate
        self.recoveries = 0  # times the gate's patience ran out and P was widened
        self.last_nis: float | None = None  # normalised innovation squared of the last update
        self._refused = 0  # consecutive refusals
        self._since = np.zeros(2)  # distance [m] and |angle| [rad] moved since the last correction
        self._track = max(float(context.robot.track_width), MIN_TRACK)  # [m] nominal

    def update(self, inputs: LocalizerInputs) -> None:
        odom = np.asarray(inputs.odometry, dtype=float)
        if self._odom is not None:
            self._predict(between(self._odom, odom))
        self._odom = odom.copy()
        scan = inputs.scan
        if scan is not None and abs(scan.time - inputs.time) < 1e-9:
            self._correct(scan)

    def debug(self) -> dict[str, Any]:
        return {"updates": self.updates, "rejected": self.rejected, "nis": self.last_nis,
                "recoveries": self.recoveries}

    @property
    def localized(self) -> bool:
        """Its covariance is within the bounds (a kidnapped or lost filter widens it)."""
        return self.spread_within_bounds()

    def _predict(self, u: np.ndarray) -> None:
        c = self.config
        theta = self.pose[2]
        cs, sn = np.cos(theta), np.sin(theta)
        f = np.array([[1.0, 0.0, -sn * u[0] - cs * u[1]],
                      [0.0, 1.0, cs * u[0] - sn * u[1]],
                      [0.0, 0.0, 1.0]])
        g = np.array([[cs, -sn, 0.0], [sn, cs, 0.0], [0.0, 0.0, 1.0]])
        d, a = float(np.hypot(u[0], u[1])), abs(float(u[2]))
        q = np.diag([c.trans_noise ** 2 * d, c.trans_noise ** 2 * d,
                     c.rot_noise ** 2 * d + c.turn_noise ** 2 * a])
        self.pose = compose(self.pose, u)
        self.covariance = f @ self.covariance @ f.T + g @ q @ g.T
        self._since += (d, a)

    def _add_calibration_error(self) -> None:
        """P += the systematic error over the motion since the last correction (robot frame)."""
        c = self.config.calibration_error
        d, a = self._since
        self._since[:] = 0.0
        cs, sn = np.cos(self.pose[2]), np.sin(self.pose[2])
        g = np.array([[cs, -sn, 0.0], [sn, cs, 0.0], [0.0, 0.0, 1.0]])
        q = np.diag([(c * d) ** 2, (c * d) ** 2, (c * a + c * d / self._track) ** 2])
        self.covariance = self.covariance + g @ q @ g.T

    def _correct(self, scan) -> None:
        c = self.config
        points = subsample(scan_points(scan)[0], c.max_beams)
        if c.reject_short and points.shape[0]:
            # returns short of the map from the predicted pose (people) are left out
            kept = points[~short_returns(self.field, self.pose, points, (scan.offset[0], scan.offset[1]),
                                         scan.max_range, c.short_margin)]
            points = kept if kept.shape[0] >= MIN_POINTS else points
        match = match_scan(self.field, points, self.pose, c.iterations,
                           c.huber, c.match_cov_scale)
        if not match.ok:
            return
        self._add_calibration_error()
        innovation = match.pose - self.pose
        innovation[2] = wrap(innovation[2])
        r = match.covariance + np.diag([c.map_std ** 2, c.map_std ** 2, 0.0])
        s_inv = np.linalg.inv(self.covariance + r)
        nis = float(innovation @ s_inv @ innovation)
        if nis > c.gate:
            self.rejected += 1
            self._refused += 1
            if self._refused < c.gate_patience:
                return
            # The scans keep disagreeing with a confident filter: believe the disagreement.
            self.covariance = self.covariance + np.diag(np.square(innovation))
            s_inv = np.linalg.inv(self.covariance + r)
            self.recoveries += 1
        self._refused = 0
        k = self.covariance @ s_inv
        self.pose = self.pose + k @ innovation
        self.pose[2] = float(wrap(self.pose[2]))
        i_k = np.eye(3) - k
        self.covariance = i_k @ self.covariance @ i_k.T + k @ r @ k.T
        self.updates += 1
        self.last_nis = nis
