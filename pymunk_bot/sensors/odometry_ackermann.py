"""Car odometry: rear-wheel encoders give the distance, a steering-angle sensor the turning.

Per tick: ds = mean of the two measured rear-wheel travels (encoder model in
:mod:`.encoders`); the steering sensor reads the tick's mean steering angle as
delta_m = delta * (1 + steer_scale_error) + steer_offset, rounded to ``steer_resolution``; the
heading changes by ds * tan(delta_m) / believed wheelbase, plus a random walk of
``steer_noise_std`` [rad per sqrt(m)] scaled like a steering error (sec^2(delta) / wheelbase).
The pose moves along the exact arc. ``covariance`` propagates the random parts (travel noise,
steering noise) with the linearised model; systematic errors are not in it (the robot cannot
know them).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pymunk_bot.robots.rows import OWN, Rows
from pymunk_bot.sensors.encoders import EncoderBank, OdometryHandle, integrate_twist


class AckermannOdometryGroup:
    """Dead reckoning of every car of a world; ``update`` takes the drive's travel rows
    (rear-left [m], rear-right [m], integral of tan(delta) ds [m])."""

    ROWS = ("pose", "wheel_travel", "steering", "covariance")  # per robot (and the encoders')

    def __init__(self, configs: Sequence[Any], wheelbase: np.ndarray, track: np.ndarray,
                 rngs: Sequence[np.random.Generator], rows: Rows = OWN) -> None:
        self.configs = list(configs)
        self.geometry = (np.asarray(wheelbase, dtype=float), np.asarray(track, dtype=float))
        odo = [c.odometry for c in self.configs]
        n = len(odo)
        self.rngs = list(rngs)
        self.pose = rows.hold("pose", np.array([c.pose for c in self.configs],
                                               dtype=float).reshape(n, 3))
        self.encoders = EncoderBank(
            np.array([(1 + o.left_scale_error, 1 + o.right_scale_error) for o in odo]).reshape(n, 2),
            np.array([o.wheel_noise_std ** 2 for o in odo]),
            np.array([o.encoder_resolution for o in odo]), self.rngs, rows.within("encoders"))
        self.believed_wheelbase = np.array(
            [w * (1 + o.wheelbase_error) for w, o in zip(wheelbase, odo)])  # [m]
        self.steer_scale = np.array([1 + o.steer_scale_error for o in odo])
        self.steer_offset = np.array([o.steer_offset for o in odo])  # [rad]
        self.steer_resolution = np.array([o.steer_resolution for o in odo])  # [rad]
        self.steer_var = np.array([o.steer_noise_std ** 2 for o in odo])  # [rad^2 per m]
        self._steer_noisy = np.flatnonzero(self.steer_var > 0).tolist()
        self._random = sorted(set(self.encoders.noisy) | set(self._steer_noisy))
        # measured rear-wheel travel [m]
        self.wheel_travel = rows.hold("wheel_travel", np.zeros((n, 2)))
        self.steering = rows.hold("steering", np.zeros(n))  # the steering sensor's last [rad]
        self.covariance = rows.hold("covariance", np.zeros((n, 3, 3)))

    @classmethod
    def stacked(cls, parts: list["AckermannOdometryGroup"],
                rows: Rows) -> "AckermannOdometryGroup":
        """The groups of copies as one on ``rows``, the whole of the rows the parts hold (see
        :mod:`pymunk_bot.robots.rows`), drawing from the same generators."""
        return cls([c for part in parts for c in part.configs],
                   np.concatenate([part.geometry[0] for part in parts]),
                   np.concatenate([part.geometry[1] for part in parts]),
                   [rng for part in parts for rng in part.rngs], rows)

    def update(self, travel: Any) -> None:
        travel = np.asarray(travel, dtype=float)
        true_ds = 0.5 * (travel[:, 0] + travel[:, 1])
        moving = np.abs(true_ds) > 1e-12
        mean_tan = np.divide(travel[:, 2], true_ds, out=np.zeros_like(true_ds), where=moving)
        steer = np.arctan(mean_tan) * self.steer_scale + self.steer_offset
        q = self.steer_resolution > 0
        if q.any():
            steer[q] = np.round(steer[q] / self.steer_resolution[q]) * self.steer_resolution[q]
        np.copyto(self.steering, steer, where=moving)  # in place: see ROWS
        wheels = self.encoders.measure(travel[:, :2])
        self.wheel_travel += wheels
        ds = 0.5 * (wheels[:, 0] + wheels[:, 1])
        kappa = np.tan(steer) / self.believed_wheelbase  # [1/m]
        dtheta = ds * kappa
        heading_gain = (1.0 + np.tan(steer) ** 2) / self.believed_wheelbase  # d kappa / d delta
        for i in self._steer_noisy:
            if true_ds[i] != 0.0:
                dtheta[i] += (np.sqrt(self.steer_var[i] * abs(true_ds[i])) * heading_gain[i]
                              * self.rngs[i].standard_normal())
        c, s, chord = integrate_twist(self.pose, ds, np.zeros_like(ds), dtheta)
        if self._random:
            self._propagate(np.array(self._random), c, s, chord * ds, kappa, heading_gain,
                            np.abs(wheels), np.abs(true_ds))

    def _propagate(self, i: np.ndarray, c: np.ndarray, s: np.ndarray, chord: np.ndarray,
                   kappa: np.ndarray, gain: np.ndarray, abs_wheels: np.ndarray,
                   abs_ds: np.ndarray) -> None:
        """P <- F P F^T + G Q G^T with inputs (ds, heading noise)."""
        m = len(i)
        f = np.tile(np.eye(3), (m, 1, 1))
        f[:, 0, 2] = -chord[i] * s[i]
        f[:, 1, 2] = chord[i] * c[i]
        g = np.zeros((m, 3, 2))
        g[:, 0, 0], g[:, 1, 0], g[:, 2, 0] = c[i], s[i], kappa[i]
        g[:, 0, 1], g[:, 1, 1], g[:, 2, 1] = -0.5 * chord[i] * s[i], 0.5 * chord[i] * c[i], 1.0
        q = np.zeros((m, 2))
        q[:, 0] = self.encoders.noise_var[i] * abs_wheels[i].sum(axis=1) / 4.0  # var(mean of 2)
        q[:, 1] = self.steer_var[i] * abs_ds[i] * gain[i] ** 2
        p = self.covariance[i]
        self.covariance[i] = f @ p @ f.transpose(0, 2, 1) + (g * q[:, None, :]) @ g.transpose(0, 2, 1)

    def handle(self, i: int) -> OdometryHandle:
        return OdometryHandle(self, i)


def of_ackermann_drive(group: Any, rngs: Sequence[np.random.Generator],
                       rows: Rows = OWN) -> Any:
    """The odometry of every robot of a drive ``group`` (one generator each), its per-robot
    state on ``rows``: what ``plugins.odometry`` pairs with the drive of the same name."""
    return AckermannOdometryGroup(group.configs, group.wheelbase, group.track, rngs, rows)
