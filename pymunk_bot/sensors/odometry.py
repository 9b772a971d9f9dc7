"""Wheel odometry integrated from simulated encoders, with the errors real encoders have.

Per wheel and tick, the encoder measures the travel of that wheel as the motor turned it:
    measured = true * (1 + scale_error) + noise,  noise ~ N(0, wheel_noise_std^2 * |true|)
then (optionally) rounded down to whole encoder ticks. Variance proportional to distance makes
the error a random walk in travelled distance, independent of the time step. The pose is
integrated along exact arcs with the track width the robot believes it has.

When a wheel slips (the robot pushes a wall or a crate too heavy for its motors) the encoders
still count the wheel's rotation, so odometry runs ahead of the true pose, as on a real robot.
"""
from __future__ import annotations

import math

import numpy as np

from ..config.schema import OdometryConfig
from ..drive import sinc_half


class Odometry:
    """Dead reckoning from the left and right wheel encoders."""

    def __init__(self, config: OdometryConfig, start_pose, track_width: float,
                 rng: np.random.Generator) -> None:
        self.config = config
        self._rng = rng
        self._x, self._y, self._theta = (float(v) for v in start_pose)
        self._believed_track = track_width * (1.0 + config.track_width_error)
        self._scale = (1.0 + config.left_scale_error, 1.0 + config.right_scale_error)
        self._noise_var = config.wheel_noise_std ** 2
        self._cumulative = [0.0, 0.0]  # measured travel before quantisation [m]
        self._ticks = [0, 0]  # whole encoder ticks counted so far

    @property
    def pose(self) -> np.ndarray:
        """The odometry estimate [x, y, theta] (theta unwrapped)."""
        return np.array([self._x, self._y, self._theta])

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
        ds = 0.5 * (left + right)
        dtheta = (right - left) / self._believed_track
        chord = ds * sinc_half(dtheta)
        heading = self._theta + 0.5 * dtheta
        self._x += chord * math.cos(heading)
        self._y += chord * math.sin(heading)
        self._theta += dtheta
