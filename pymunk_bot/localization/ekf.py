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
- **No lock-out.** ``gate_patience`` good matches in a row refused by the gate, which agree
  with each other (each carried to the latest through the odometry since, within the gate
  under both matches' covariances and the motion's noise), mean the filter, not the scans, is
  wrong (its noise model was too optimistic): P is widened by the squared innovation and the
  match is folded in, so the filter recovers instead of coasting on odometry forever. Refused
  matches that disagree among themselves are the scans' fault: a match that slid along an
  aisle whose ends the LiDAR cannot see lands somewhere else each scan (measured: warehouse,
  3.5 m range, 13, 17, 14, 42, 46 cm along the aisle in five scans, each claiming 2-4 cm), and
  is not believed.
- **Heading from a refused match.** A match that slid along an aisle still has the heading
  right: long walls fix it however far the match slid (measured on the slid matches above:
  within 0.3 deg, from starts 3-15 deg off). So a refused match's heading alone is tested, by
  the heading's own gate (chi^2 with one degree of freedom at the same confidence), and folded
  in when it passes (H = [0, 0, 1]). Without it a refusal left the heading to the odometry, the
  next match started further off and slid further, and the filter drifted 50 cm in a second.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.config.localization import EkfConfig
from pymunk_bot.localization.dynamic import short_returns
from pymunk_bot.localization.scanmatch import MIN_POINTS, match_scan, subsample
from pymunk_bot.localization.se2 import between, compose, scan_points, wrap

HEADING_GATE = 10.83  # chi^2(1) at 99.9 %, the confidence of the default ``gate`` (chi^2(3))
MIN_TRACK = 0.1  # [m] the lever for heading drift when the robot has no wheel track (omni)


class EkfLocalizer(Localizer):
    """Extended Kalman filter localization with scan-to-map matching as the measurement."""

    needs_map = True
    needs_lidar = True

    def __init__(self, config: EkfConfig, context: LocalizerContext) -> None:
        super().__init__(config, context)
        if context.map is None:
            raise ValueError("ekf needs a map (the scenario's, or world.map)")
        self.field = context.likelihood_field(config.max_dist)
        self.covariance = np.diag(np.square(config.initial_std))
        self._odom: np.ndarray | None = None
        self.updates = 0  # scans folded in
        self.rejected = 0  # matches refused by the gate
        self.recoveries = 0  # times the gate's patience ran out and P was widened
        self.heading_updates = 0  # refused matches whose heading was folded in
        self.last_nis: float | None = None  # normalised innovation squared of the last update
        self._refused: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # refused in a
        # row: (matched pose, its covariance, the odometry pose at its scan)
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
                "recoveries": self.recoveries, "heading_updates": self.heading_updates}

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
        q = np.diag(self._random_motion_noise(d, a))
        self.pose = compose(self.pose, u)
        self.covariance = f @ self.covariance @ f.T + g @ q @ g.T
        self._since += (d, a)

    def _random_motion_noise(self, d: float, a: float) -> np.ndarray:
        """The variances [m^2, m^2, rad^2] (along, across, heading) the encoders' random noise
        adds over ``d`` [m] driven and ``a`` [rad] turned."""
        c = self.config
        return np.array([c.trans_noise ** 2 * d, c.trans_noise ** 2 * d,
                         c.rot_noise ** 2 * d + c.turn_noise ** 2 * a])

    def _calibration_noise(self, d: float, a: float) -> np.ndarray:
        """The variances [m^2, m^2, rad^2] the systematic odometry error can make over ``d``
        [m] driven and ``a`` [rad] turned."""
        c = self.config.calibration_error
        return np.array([(c * d) ** 2, (c * d) ** 2, (c * a + c * d / self._track) ** 2])

    def _add_calibration_error(self) -> None:
        """P += the systematic error over the motion since the last correction (robot frame)."""
        d, a = self._since
        self._since[:] = 0.0
        cs, sn = np.cos(self.pose[2]), np.sin(self.pose[2])
        g = np.array([[cs, -sn, 0.0], [sn, cs, 0.0], [0.0, 0.0, 1.0]])
        q = np.diag(self._calibration_noise(d, a))
        self.covariance = self.covariance + g @ q @ g.T

    def _correct_heading(self, innovation: float, variance: float) -> None:
        """Fold in a match's heading alone (``innovation`` [rad], its ``variance`` [rad^2]) if
        it passes the heading's gate."""
        p = self.covariance
        s = float(p[2, 2]) + variance
        if innovation * innovation > HEADING_GATE * s:
            return
        k = p[:, 2] / s
        self.pose = self.pose + k * innovation
        self.pose[2] = float(wrap(self.pose[2]))
        i_k = np.eye(3)
        i_k[:, 2] -= k
        self.covariance = i_k @ p @ i_k.T + variance * np.outer(k, k)
        self.heading_updates += 1

    def _refusals_agree(self) -> bool:
        """Whether every refused match, carried to the latest one's scan through the odometry
        since, lies within the gate of it (their covariances plus the motion's noise, as an
        isotropic bound in x and y: the motion's frame turns along the way)."""
        last_pose, last_cov, last_odom = self._refused[-1]
        for pose, cov, odom in self._refused[:-1]:
            motion = between(odom, last_odom)
            d, a = float(np.hypot(motion[0], motion[1])), abs(float(motion[2]))
            noise = self._random_motion_noise(d, a) + self._calibration_noise(d, a)
            q = np.diag([noise[0] + noise[1], noise[0] + noise[1], noise[2]])
            carried = compose(pose, motion)
            gap = last_pose - carried
            gap[2] = wrap(gap[2])
            if float(gap @ np.linalg.solve(cov + last_cov + q, gap)) > self.config.gate:
                return False
        return True

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
            assert self._odom is not None  # a scan comes with the odometry of its tick
            self._refused.append((match.pose.copy(), r, self._odom.copy()))
            patience_out = len(self._refused) >= c.gate_patience
            if not (patience_out and self._refusals_agree()):
                if patience_out:
                    self._refused.pop(0)  # the oldest leaves; the next is tested with the rest
                self._correct_heading(innovation[2], r[2, 2])  # refused: its heading alone
                return
            # The scans keep disagreeing with a confident filter: believe the disagreement.
            self.covariance = self.covariance + np.diag(np.square(innovation))
            s_inv = np.linalg.inv(self.covariance + r)
            self.recoveries += 1
        self._refused.clear()
        k = self.covariance @ s_inv
        self.pose = self.pose + k @ innovation
        self.pose[2] = float(wrap(self.pose[2]))
        i_k = np.eye(3) - k
        self.covariance = i_k @ self.covariance @ i_k.T + k @ r @ k.T
        self.updates += 1
        self.last_nis = nis
