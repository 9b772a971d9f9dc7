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

import math

import numpy as np

from ..config.schema import OdometryConfig
from ..drive import sinc_half


class Odometry:
    """Dead reckoning from the left and right wheel encoders, fed each tick's true wheel travel."""

    def __init__(self, config: OdometryConfig, start_pose, track_width: float,
                 rng: np.random.Generator) -> None:
        self.config = config
        self._rng = rng
        self._x, self._y, self._theta = (float(v) for v in start_pose)
        self._believed_track = track_width * (1.0 + config.track_width_error)  # [m]
        self._scale = (1.0 + config.left_scale_error, 1.0 + config.right_scale_error)
        self._noise_var = config.wheel_noise_std ** 2  # [m^2 per m travelled]
        self._cumulative = [0.0, 0.0]  # measured travel before quantisation [m]
        self._ticks = [0, 0]  # whole encoder ticks counted so far
        self._wheel_travel = [0.0, 0.0]  # what odometry has integrated per wheel [m]
        # Upper triangle of the 3x3 pose covariance: xx, xy, xt, yy, yt, tt.
        self._cov = [0.0] * 6

    @property
    def pose(self) -> np.ndarray:
        """The odometry estimate [x, y, theta] (theta unwrapped)."""
        return np.array([self._x, self._y, self._theta])

    @property
    def wheel_travel(self) -> tuple[float, float]:
        """Measured (left, right) wheel travel since the start [m], as the encoders report it."""
        return (self._wheel_travel[0], self._wheel_travel[1])

    @property
    def covariance(self) -> np.ndarray:
        """3x3 covariance of [x, y, theta] that the encoder noise model predicts [m^2, m rad, rad^2]."""
        xx, xy, xt, yy, yt, tt = self._cov
        return np.array([[xx, xy, xt], [xy, yy, yt], [xt, yt, tt]])

    def _measure(self, wheel: int, travel: float) -> float:
        measured = travel * self._scale[wheel]
        if self._noise_var > 0.0 and travel != 0.0:
            measured += math.sqrt(self._noise_var * abs(travel)) * self._rng.standard_normal()
        resolution = self.config.encoder_resolution
        if resolution <= 0.0:
            return measured
        self._cumulative[wheel] += measured
        ticks = math.floor(self._cumulative[wheel] / resolution)
        delta, self._ticks[wheel] = ticks - self._ticks[wheel], ticks
        return delta * resolution

    def update(self, left_travel: float, right_travel: float) -> None:
        """Integrate one tick's true wheel travel [m]."""
        left = self._measure(0, left_travel)
        right = self._measure(1, right_travel)
        self._wheel_travel[0] += left
        self._wheel_travel[1] += right
        ds = 0.5 * (left + right)
        dtheta = (right - left) / self._believed_track
        chord = ds * sinc_half(dtheta)
        heading = self._theta + 0.5 * dtheta
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        if self._noise_var > 0.0:
            self._propagate(chord, cos_h, sin_h, ds, abs(left), abs(right))
        self._x += chord * cos_h
        self._y += chord * sin_h
        self._theta += dtheta

    def _propagate(self, chord: float, cos_h: float, sin_h: float, ds: float,
                   abs_left: float, abs_right: float) -> None:
        """P <- F_pose P F_pose^T + F_wheels diag(q_l, q_r) F_wheels^T (midpoint-heading model)."""
        xx, xy, xt, yy, yt, tt = self._cov
        a, b = -chord * sin_h, chord * cos_h  # d(x, y)/d theta
        xx, xy, xt = xx + 2.0 * a * xt + a * a * tt, xy + a * yt + b * xt + a * b * tt, xt + a * tt
        yy, yt = yy + 2.0 * b * yt + b * b * tt, yt + b * tt
        # d(x, y, theta)/d(left, right): half the travel each, plus the heading's effect on x, y.
        k = ds / (2.0 * self._believed_track)
        g = 1.0 / self._believed_track
        jl = (0.5 * cos_h + k * sin_h, 0.5 * sin_h - k * cos_h, -g)
        jr = (0.5 * cos_h - k * sin_h, 0.5 * sin_h + k * cos_h, g)
        ql, qr = self._noise_var * abs_left, self._noise_var * abs_right
        self._cov = [
            xx + ql * jl[0] * jl[0] + qr * jr[0] * jr[0],
            xy + ql * jl[0] * jl[1] + qr * jr[0] * jr[1],
            xt + ql * jl[0] * jl[2] + qr * jr[0] * jr[2],
            yy + ql * jl[1] * jl[1] + qr * jr[1] * jr[1],
            yt + ql * jl[1] * jl[2] + qr * jr[1] * jr[2],
            tt + ql * jl[2] * jl[2] + qr * jr[2] * jr[2],
        ]
