"""The pedestrians' true states, for controllers that assume them known (CrowdNav's setting:
its robot policies read every human's position, velocity and radius, not a LiDAR).

A robot with ``crowd_state: {...}`` gets this sensor; its controller reads
``obs.extra["crowd_state"]``, a :class:`CrowdState` of the nearest ``max_humans`` pedestrians
(nearest first) at the control tick, taken from their bodies when read.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np
import pymunk

from pymunk_bot.config.crowd_state import CrowdStateConfig


@dataclass(frozen=True)
class CrowdState:
    """The nearest pedestrians at one instant, nearest first (world frame, SI)."""

    time: float  # [s]
    positions: np.ndarray  # (k, 2) [m] centres
    velocities: np.ndarray  # (k, 2) [m/s]
    radii: np.ndarray  # (k,) [m]

    def offsets(self, xy: Sequence[float]) -> np.ndarray:
        """Each pedestrian's centre relative to the point ``xy`` [m] (world axes), (k, 2)."""
        return self.positions - np.asarray(xy, dtype=float)[:2]


class CrowdStateSensor:
    """Reads the pedestrians' bodies when its reading is asked for (``passive``: no work per
    tick). ``walkers`` gives the pedestrians (objects with ``body`` and ``config.radius``),
    asked once, on the first reading (the crowd exists by then)."""

    name = "crowd_state"
    passive = True

    def __init__(self, config: CrowdStateConfig, body: pymunk.Body,
                 walkers: Callable[[], list[Any]], clock: Callable[[], float]) -> None:
        self.config = config
        self._body = body
        self._walkers_of = walkers
        self._bodies: list[pymunk.Body] | None = None
        self._radii = np.zeros(0)
        self._clock = clock

    def update(self, time: float) -> None:
        """Nothing to do: the state is read when asked for."""

    @property
    def reading(self) -> CrowdState:
        """The nearest pedestrians now."""
        if self._bodies is None:
            walkers = self._walkers_of()
            self._bodies = [w.body for w in walkers]
            self._radii = np.array([float(w.config.radius) for w in walkers], dtype=float)
        n = len(self._bodies)
        pos, vel = np.empty((n, 2)), np.empty((n, 2))
        for i, b in enumerate(self._bodies):
            pos[i] = tuple(b.position)
            vel[i] = tuple(b.velocity)
        x, y = self._body.position
        dist = np.hypot(pos[:, 0] - x, pos[:, 1] - y)
        limit = self.config.max_range if self.config.max_range is not None else math.inf
        order = np.argsort(dist, kind="stable")
        order = order[dist[order] <= limit][:self.config.max_humans]
        return CrowdState(float(self._clock()), pos[order], vel[order], self._radii[order])
