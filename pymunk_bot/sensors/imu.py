"""A planar IMU at the robot's centre: a yaw-rate gyro and a two-axis accelerometer.

Ground truth comes from the robot body after each tick: the yaw rate is the body's angular
velocity [rad/s]; the linear acceleration is the change of the body's world-frame velocity
since the previous reading divided by the time between them, rotated into the robot frame at
the mean heading of that interval (x forward, y to the left; no gravity in a top-down world).
pymunk moves a body with the velocity it has after a step during the next substep h, so that
velocity points along the heading half a substep later; the mean heading is shifted by
omega * h / 2 to match (without it an arc would show a spurious forward acceleration).
Measurement model, per reading k taken dt_k after the previous one:
    yaw_rate = true + b_g,k + N(0, gyro_noise_std^2)
    accel    = true + b_a,k + N(0, accel_noise_std^2 I)
    b_g,k = gyro_bias + random walk with std gyro_bias_walk * sqrt(t_k)
    b_a,k = accel_bias + random walk with std accel_bias_walk * sqrt(t_k) per axis
"""
from __future__ import annotations

import math
from typing import Callable
from dataclasses import dataclass

import numpy as np
import pymunk

from pymunk_bot.config.schema import ImuConfig
from pymunk_bot.sensors.schedule import Schedule


@dataclass(frozen=True)
class ImuReading:
    """One IMU measurement."""

    time: float  # when it was taken [s]
    yaw_rate: float  # [rad/s], counter-clockwise positive
    accel: tuple[float, float]  # linear acceleration in the robot frame, (forward, left) [m/s^2]


class Imu:
    """Reads the robot body at its rate (every tick when ``rate`` is None)."""

    name = "imu"

    def __init__(self, config: ImuConfig, body: pymunk.Body, rng: np.random.Generator,
                 substep: float | Callable[[], float] = 0.0, start_time: float = 0.0) -> None:
        self.config = config
        self._body = body
        # [s] the pymunk step the body's velocity now moves in (a number, or read each time)
        self._substep: Callable[[], float] = substep if callable(substep) else (lambda: substep)
        self._rng = rng
        self._schedule = Schedule(config.rate, start_time)
        self._gyro_bias = float(config.gyro_bias)  # [rad/s], drifts with gyro_bias_walk
        self._accel_bias = [float(v) for v in config.accel_bias]  # [m/s^2]
        self._last_time: float | None = None
        self._last_velocity = (0.0, 0.0)
        self._last_angle = 0.0
        self.reading: ImuReading | None = None  # None until the first reading

    @property
    def yaw_rate(self) -> float | None:
        """Latest measured yaw rate [rad/s]."""
        return None if self.reading is None else self.reading.yaw_rate

    @property
    def accel(self) -> tuple[float, float] | None:
        """Latest measured linear acceleration in the robot frame (forward, left) [m/s^2]."""
        return None if self.reading is None else self.reading.accel

    @property
    def bias(self) -> tuple[float, float, float]:
        """The current (gyro [rad/s], accel x, accel y [m/s^2]) biases: hidden truth, for tests
        and for scoring an estimator, not something the robot could read."""
        return (self._gyro_bias, self._accel_bias[0], self._accel_bias[1])

    def update(self, time: float) -> None:
        """Take a reading if one is due at ``time`` [s] (called after every tick)."""
        if self._schedule.due(time):
            self.reading = self._measure(time)

    def _true_accel(self, time: float) -> tuple[float, float]:
        v = self._body.velocity
        angle = self._body.angle
        if self._last_time is None or time <= self._last_time:
            # The first reading: every body starts at rest, so there is no acceleration yet.
            ax = ay = 0.0
        else:
            elapsed = time - self._last_time
            awx = (v.x - self._last_velocity[0]) / elapsed
            awy = (v.y - self._last_velocity[1]) / elapsed
            mid = 0.5 * (angle + self._last_angle + self._body.angular_velocity * self._substep())
            c, s = math.cos(mid), math.sin(mid)
            ax, ay = c * awx + s * awy, -s * awx + c * awy
        self._last_time, self._last_velocity, self._last_angle = time, (v.x, v.y), angle
        return ax, ay

    def _measure(self, time: float) -> ImuReading:
        c, rng = self.config, self._rng
        elapsed = 0.0 if self._last_time is None else max(0.0, time - self._last_time)
        ax, ay = self._true_accel(time)
        if c.gyro_bias_walk > 0.0 and elapsed > 0.0:
            self._gyro_bias += c.gyro_bias_walk * math.sqrt(elapsed) * rng.standard_normal()
        if c.accel_bias_walk > 0.0 and elapsed > 0.0:
            walk = c.accel_bias_walk * math.sqrt(elapsed) * rng.standard_normal(2)
            self._accel_bias[0] += float(walk[0])
            self._accel_bias[1] += float(walk[1])
        yaw_rate = self._body.angular_velocity + self._gyro_bias
        if c.gyro_noise_std > 0.0:
            yaw_rate += c.gyro_noise_std * rng.standard_normal()
        ax += self._accel_bias[0]
        ay += self._accel_bias[1]
        if c.accel_noise_std > 0.0:
            noise = c.accel_noise_std * rng.standard_normal(2)
            ax += float(noise[0])
            ay += float(noise[1])
        return ImuReading(time=time, yaw_rate=float(yaw_rate), accel=(float(ax), float(ay)))
