"""Wheel odometry integrated from simulated encoders, with the errors real encoders have.

Per wheel and tick, the encoder measures the travel of that wheel as the motor turned it:
    measured = true * (1 + scale_error) + noise,  noise ~ N(0, wheel_noise_std^2 * |true|)
then (optionally) quantised: the encoder counts whole ticks of ``encoder_resolution`` metres of
cumulative measured travel. Variance proportional to distance makes the error a random walk in
travelled distance, independent of the time step. The pose is integrated along exact arcs with
the track width the robot believes it has, true * (1 + track_width_error).

When a wheel slips (the robot pushes a wall or a crate too heavy for its motors) the encoders
still count the wheel's rotation, so odometry runs ahead of the true pose, as on a real robot.
Conversely, a robot shoved sideways or pushed while its wheels stand still does not notice.

``covariance`` is the uncertainty the random encoder noise predicts for the estimate, propagated
with the linearised motion model each tick (what a ROS odometry publisher reports). The robot
cannot know its scale and track errors, so their systematic drift is not in it.
"""
from __future__ import annotations

from typing import Any, Sequence

import numba
import numpy as np

from pymunk_bot.geometry.arcs import arc_step
from pymunk_bot.robots.rows import OWN, Rows
from pymunk_bot.sensors.encoders import EncoderBank


class DiffOdometryGroup:
    """Dead reckoning of every diff-drive robot of a world, as arrays; fed each tick's true
    wheel travel. Random draws come from each robot's own generator, in a fixed order, so a
    robot's odometry does not depend on which other robots exist."""

    ROWS = ("pose", "wheel_travel", "covariance")  # the per-robot state (and the encoders')

    def __init__(self, configs: Sequence[Any], start_poses: Sequence[Sequence[float]],
                 track_widths: Sequence[float], rngs: Sequence[np.random.Generator],
                 rows: Rows = OWN) -> None:
        self.configs = list(configs)
        self.track_widths = list(track_widths)  # [m] the true ones
        n = len(self.configs)
        self.rngs = list(rngs)
        # [x, y, theta] (unwrapped)
        self.pose = rows.hold("pose", np.array(start_poses, dtype=float).reshape(n, 3))
        self.believed_track = np.array(
            [t * (1.0 + c.track_width_error) for t, c in zip(track_widths, configs)])  # [m]
        self.scale = np.array([(1.0 + c.left_scale_error, 1.0 + c.right_scale_error)
                               for c in configs]).reshape(n, 2)
        self.noise_var = np.array([c.wheel_noise_std ** 2 for c in configs])  # [m^2 per m]
        self.encoders = EncoderBank(self.scale, self.noise_var,
                                    np.array([c.encoder_resolution for c in configs]), self.rngs,
                                    rows.within("encoders"))
        self._noisy = self.encoders.noisy
        # what odometry has integrated per wheel [m]
        self.wheel_travel = rows.hold("wheel_travel", np.zeros((n, 2)))
        self.covariance = rows.hold("covariance", np.zeros((n, 3, 3)))
        # Encoders that only scale are applied in the compiled step (dead_reckon, which the
        # engine's bookkeeping pass calls too); others measure first.
        self.plain = not self._noisy and not self.encoders.quantised
        self._unit_scale = np.ones((n, 2))
        self._mid = np.empty((3, n))  # cos, sin of the mid-step heading and chord factor

    @classmethod
    def stacked(cls, parts: list["DiffOdometryGroup"], rows: Rows) -> "DiffOdometryGroup":
        """The groups of copies as one on ``rows``, the whole of the rows the parts hold (see
        :mod:`pymunk_bot.robots.rows`), drawing from the same generators."""
        configs = [c for part in parts for c in part.configs]
        return cls(configs, [(0.0, 0.0, 0.0)] * len(configs),
                   [t for part in parts for t in part.track_widths],
                   [rng for part in parts for rng in part.rngs], rows)

    def update(self, travel: Any) -> None:
        """Integrate one tick's true (left, right) wheel travel [m], shape (n, 2)."""
        if not isinstance(travel, np.ndarray):
            travel = np.asarray(travel, dtype=float)
        self._integrate(travel, False)

    def take(self, travel: np.ndarray) -> None:
        """:meth:`update` with the drive's accumulated ``travel`` (n, 2) [m], then zeroed in
        place (``DriveGroup.travel``): one compiled call where the encoders only scale."""
        if self.plain:  # the usual case (no noise, no quantising): _integrate's first branch
            dead_reckon(travel, self.scale, self.believed_track, self.wheel_travel, self.pose,
                        self._mid, True)
            return
        self._integrate(travel, True)

    def _integrate(self, travel: np.ndarray, taken: bool) -> None:
        """Dead reckoning from ``travel`` (n, 2) [m], zeroed after if ``taken``."""
        if self.plain:
            dead_reckon(travel, self.scale, self.believed_track, self.wheel_travel, self.pose,
                        self._mid, taken)
            wheels = travel  # (not read again: plain encoders have no noise to propagate)
        else:
            wheels = self.encoders.measure(travel)
            if taken:
                travel.fill(0.0)
            dead_reckon(wheels, self._unit_scale, self.believed_track, self.wheel_travel,
                        self.pose, self._mid, False)
        if self._noisy:
            cos_h, sin_h, factor = self._mid
            ds = 0.5 * (wheels[:, 0] + wheels[:, 1])
            self._propagate(ds * factor, cos_h, sin_h, ds, np.abs(wheels))

    def _propagate(self, chord: np.ndarray, cos_h: np.ndarray, sin_h: np.ndarray,
                   ds: np.ndarray, abs_wheels: np.ndarray) -> None:
        """P <- F_pose P F_pose^T + F_wheels diag(q_l, q_r) F_wheels^T (midpoint-heading model)."""
        i = np.array(self._noisy)
        c, s, track = cos_h[i], sin_h[i], self.believed_track[i]
        f = np.zeros((len(i), 3, 3))
        f[:, 0, 0] = f[:, 1, 1] = f[:, 2, 2] = 1.0
        f[:, 0, 2] = -chord[i] * s  # d(x, y)/d theta
        f[:, 1, 2] = chord[i] * c
        # d(x, y, theta)/d(left, right): half the travel each, plus the heading's effect on x, y.
        k = ds[i] / (2.0 * track)
        g = np.zeros((len(i), 3, 2))
        g[:, :, 0] = np.stack((0.5 * c + k * s, 0.5 * s - k * c, -1.0 / track), axis=1)
        g[:, :, 1] = np.stack((0.5 * c - k * s, 0.5 * s + k * c, 1.0 / track), axis=1)
        q = self.noise_var[i, None] * abs_wheels[i]  # (m, 2)
        p = self.covariance[i]
        self.covariance[i] = f @ p @ f.transpose(0, 2, 1) + (g * q[:, None, :]) @ g.transpose(0, 2, 1)


    def handle(self, i: int) -> "Odometry":
        """Robot ``i``'s view (``robot.odometry``)."""
        return Odometry(self.configs[i], (0.0, 0.0, 0.0), 0.0, self.rngs[i], group=self, index=i)


class Odometry:
    """One robot's odometry (``robot.odometry``); standalone, it dead-reckons by itself:
    ``Odometry(config, start_pose, track_width, rng).update(left_travel, right_travel)``."""

    def __init__(self, config: Any, start_pose: Sequence[float], track_width: float,
                 rng: np.random.Generator, *, group: DiffOdometryGroup | None = None,
                 index: int = 0) -> None:
        self.config = config
        self._group = group or DiffOdometryGroup([config], [start_pose], [track_width], [rng])
        self._i = index

    @property
    def pose(self) -> np.ndarray:
        """The odometry estimate [x, y, theta] (theta unwrapped)."""
        return np.array(self._group.pose[self._i], dtype=float)

    @property
    def wheel_travel(self) -> tuple[float, float]:
        """Measured (left, right) wheel travel since the start [m], as the encoders report it."""
        left, right = self._group.wheel_travel[self._i]
        return (float(left), float(right))  # a row of an array or of a list

    @property
    def covariance(self) -> np.ndarray:
        """3x3 covariance of [x, y, theta] that the encoder noise model predicts [m^2, m rad, rad^2]."""
        return self._group.covariance[self._i].copy()

    def update(self, left_travel: float, right_travel: float) -> None:
        """Integrate one tick's true wheel travel [m] (standalone use only)."""
        travel = np.zeros((len(self._group.configs), 2))
        travel[self._i] = (left_travel, right_travel)
        self._group.update(travel)


def of_diff_drive(group: Any, rngs: Sequence[np.random.Generator], rows: Rows = OWN) -> Any:
    """The odometry of every robot of a drive ``group`` (one generator each), its per-robot
    state on ``rows``: what ``plugins.odometry`` pairs with the drive of the same name."""
    return DiffOdometryGroup([c.odometry for c in group.configs], [c.pose for c in group.configs],
                             group.track.tolist(), rngs, rows)


@numba.njit(cache=True)
def dead_reckon(wheels: np.ndarray, scale: np.ndarray, track: np.ndarray,
                wheel_travel: np.ndarray, pose: np.ndarray, mid: np.ndarray,
                taken: bool) -> None:
    """Each robot's encoder readings (n, 2) [m] (times ``scale``: encoders that only scale, or
    ones) added to its wheel travel, and its pose moved along the arc they make with the track
    width it believes [m]; fills ``mid`` (3, n): the mid-step cos, sin and chord factors.
    ``taken``: ``wheels`` is zeroed once read (a drive's accumulator)."""
    for i in range(pose.shape[0]):
        left, right = wheels[i, 0] * scale[i, 0], wheels[i, 1] * scale[i, 1]
        if taken:
            wheels[i, 0] = wheels[i, 1] = 0.0
        wheel_travel[i, 0] += left
        wheel_travel[i, 1] += right
        mid[0, i], mid[1, i], mid[2, i] = arc_step(pose, i, 0.5 * (left + right), 0.0,
                                                   (right - left) / track[i])
