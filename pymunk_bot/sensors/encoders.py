"""Wheel encoders with the errors real ones have, for any number of wheels per robot.

Per wheel and tick: measured = true * (1 + scale_error) + noise, noise ~ N(0, var * |true|)
(so the error is a random walk in distance, independent of the time step), then optionally
quantised to whole ticks of ``resolution`` metres of cumulative measured travel. Every drive's
odometry reads its wheels through an :class:`EncoderBank`.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pymunk_bot.geometry.arcs import integrate_arcs
from pymunk_bot.robots.rows import OWN, Rows


class EncoderBank:
    """Encoders of every robot of a group: ``scale`` (n, k), ``noise_var`` (n,) [m^2 per m],
    ``resolution`` (n,) [m per tick]; one generator per robot, drawn in wheel order; ``rows``:
    where the per-robot state lives (:mod:`pymunk_bot.robots.rows`)."""

    ROWS = ("_cumulative", "_ticks")  # the per-robot state

    def __init__(self, scale: np.ndarray, noise_var: np.ndarray, resolution: np.ndarray,
                 rngs: Sequence[np.random.Generator], rows: Rows = OWN) -> None:
        self.scale = np.asarray(scale, dtype=float)
        self.noise_var = np.asarray(noise_var, dtype=float)
        self.resolution = np.asarray(resolution, dtype=float)
        self._rngs = list(rngs)
        self.noisy = np.flatnonzero(self.noise_var > 0.0).tolist()
        self._quantised = np.flatnonzero(self.resolution > 0.0)
        # measured travel before quantisation [m]
        self._cumulative = rows.hold("_cumulative", np.zeros_like(self.scale))
        self._ticks = rows.hold("_ticks", np.zeros_like(self.scale))  # whole ticks so far

    @property
    def quantised(self) -> bool:
        """Whether any robot's encoders count whole ticks."""
        return self._quantised.shape[0] > 0

    def measure(self, travel: np.ndarray) -> np.ndarray:
        """One tick's true wheel travel (n, k) [m] -> what the encoders report [m]."""
        measured = travel * self.scale
        for i in self.noisy:
            rng, var = self._rngs[i], self.noise_var[i]
            for wheel in range(travel.shape[1]):
                if travel[i, wheel] != 0.0:
                    measured[i, wheel] += np.sqrt(var * abs(travel[i, wheel])) * rng.standard_normal()
        q = self._quantised
        if q.shape[0]:
            self._cumulative[q] += measured[q]
            ticks = np.floor(self._cumulative[q] / self.resolution[q, None])
            measured[q] = (ticks - self._ticks[q]) * self.resolution[q, None]
            self._ticks[q] = ticks
        return measured


class OdometryHandle:
    """One robot's odometry (``robot.odometry``): ``pose`` and ``covariance`` of its group."""

    def __init__(self, group: Any, index: int) -> None:
        self._group = group
        self._i = index
        self.config = group.configs[index]

    @property
    def pose(self) -> np.ndarray:
        """The odometry estimate [x, y, theta] (theta unwrapped)."""
        return self._group.pose[self._i].copy()

    @property
    def covariance(self) -> np.ndarray:
        """3x3 covariance of [x, y, theta] the random encoder noise predicts."""
        return self._group.covariance[self._i].copy()

    @property
    def wheel_travel(self) -> tuple[float, ...]:
        """Measured travel of each wheel since the start [m], as the encoders report it."""
        return tuple(float(v) for v in self._group.wheel_travel[self._i])


def integrate_twist(pose: np.ndarray, dx: np.ndarray, dy: np.ndarray,
                    dtheta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move poses (n, 3) in place by body-frame increments along exact arcs; returns
    (cos, sin) of the mid-step heading and the chord factor, for covariance propagation."""
    n = pose.shape[0]
    c, s, chord = np.empty(n), np.empty(n), np.empty(n)
    # contiguous: one array layout for the kernel (numba compiles it once)
    integrate_arcs(pose, np.ascontiguousarray(dx, dtype=np.float64),
                   np.ascontiguousarray(dy, dtype=np.float64),
                   np.ascontiguousarray(dtheta, dtype=np.float64), c, s, chord)
    return c, s, chord
