"""Positions (of the centres of gravity) and velocities of a set of bodies, read and set by a
compiled loop through Chipmunk's own functions (:mod:`pymunk_bot.physics.chipmunk`): one path
for a few bodies and a crowd, whatever else the Space holds."""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pymunk

from pymunk_bot.physics.chipmunk import CALLS, addresses, read_poses, read_states, set_velocities


class BodyStates:
    """``read()``: an (n, 4) array of x, y [m] (centre of gravity), vx, vy [m/s] of
    ``bodies``, in their order; ``set_velocities``: theirs."""

    def __init__(self, bodies: Sequence[pymunk.Body]) -> None:
        self.bodies = list(bodies)
        self._at = addresses(self.bodies)  # valid while self.bodies keeps them alive
        self._state = np.empty((len(self.bodies), 5))  # x, y, vx, vy, omega
        self._poses = np.empty((len(self.bodies), 3))  # x, y, angle (for the cogs)
        cogs = np.array([tuple(b.center_of_gravity) for b in self.bodies]).reshape(-1, 2)
        self._cogs = cogs if cogs.any() else None  # [m] body frame, where not at the origin

    def read(self) -> np.ndarray:
        read_states(CALLS, self._at, self._state)
        mine = self._state[:, :4].copy()  # an array of its own
        if self._cogs is not None:  # from the body's origin to its centre of gravity
            read_poses(CALLS, self._at, self._poses)
            angle = self._poses[:, 2]
            c, s = np.cos(angle), np.sin(angle)
            mine[:, 0] += c * self._cogs[:, 0] - s * self._cogs[:, 1]
            mine[:, 1] += s * self._cogs[:, 0] + c * self._cogs[:, 1]
        return mine

    def set_velocities(self, velocities: np.ndarray) -> None:
        """Give the first len(``velocities``) bodies ``velocities`` (k, 2) [m/s]."""
        set_velocities(CALLS, self._at[:len(velocities)],
                       np.ascontiguousarray(velocities, dtype=np.float64))
