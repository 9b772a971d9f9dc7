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
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .base import Localizer, LocalizerContext, LocalizerInputs
from .config import EkfConfig
from .likelihood import LikelihoodField
from .scanmatch import match_scan, subsample
from .se2 import between, compose, scan_points, wrap


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
        self.last_nis: float | None = None  # normalised innovation squared of the last update

    def update(self, inputs: LocalizerInputs) -> None:
        odom = np.asarray(inputs.odometry, dtype=float)
        if self._odom is not None:
            self._predict(between(self._odom, odom))
        self._odom = odom.copy()
        scan = inputs.scan
        if scan is not None and abs(scan.time - inputs.time) < 1e-9:
            self._correct(scan)

    def debug(self) -> dict[str, Any]:
        return {"updates": self.updates, "rejected": self.rejected, "nis": self.last_nis}

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

    def _correct(self, scan) -> None:
        c = self.config
        points, _ = scan_points(scan)
        match = match_scan(self.field, subsample(points, c.max_beams), self.pose, c.iterations,
                           c.huber, c.match_cov_scale)
        if not match.ok:
            return
        innovation = match.pose - self.pose
        innovation[2] = wrap(innovation[2])
        r = match.covariance + np.diag([c.map_std ** 2, c.map_std ** 2, 0.0])
        s = self.covariance + r
        s_inv = np.linalg.inv(s)
        nis = float(innovation @ s_inv @ innovation)
        if nis > c.gate:
            self.rejected += 1
            return
        k = self.covariance @ s_inv
        self.pose = self.pose + k @ innovation
        self.pose[2] = float(wrap(self.pose[2]))
        i_k = np.eye(3) - k
        self.covariance = i_k @ self.covariance @ i_k.T + k @ r @ k.T
        self.updates += 1
        self.last_nis = nis
