"""Omni odometry: the body motion a mecanum or three-wheel omni base infers from its wheels.

Each wheel's encoder measures its rim travel (error model in :mod:`.encoders`, per-wheel scale
errors from ``scale_errors``); the body increment is the least-squares inverse of the wheel
matrix the robot believes in (``wheel_distance`` off by ``wheel_distance_error``), integrated
along the exact arc. ``covariance`` propagates the encoder noise through that inverse.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pymunk_bot.robots.drives.omni import wheel_matrix
from pymunk_bot.robots.rows import OWN, Rows
from pymunk_bot.sensors.encoders import EncoderBank, OdometryHandle, integrate_twist


class OmniOdometryGroup:
    """Dead reckoning of every omni robot of a world; ``update`` takes (n, 4) rim travel [m]."""

    ROWS = ("pose", "wheel_travel", "covariance")  # the per-robot state (and the encoders')

    def __init__(self, configs: Sequence[Any], wheels: np.ndarray,
                 rngs: Sequence[np.random.Generator], rows: Rows = OWN) -> None:
        self.configs = list(configs)
        self.wheels = np.asarray(wheels)  # the drive's true wheel matrices
        self.rngs = list(rngs)
        n = len(self.configs)
        self.pose = rows.hold("pose", np.array([c.pose for c in self.configs],
                                               dtype=float).reshape(n, 3))
        self.used = np.array([4 if c.wheels == "mecanum" else 3 for c in self.configs])
        scale = np.ones((n, 4))
        for i, c in enumerate(self.configs):
            errors = c.odometry.scale_errors[:self.used[i]]
            scale[i, :len(errors)] += errors
        self.encoders = EncoderBank(scale, np.array([c.odometry.wheel_noise_std ** 2 for c in configs]),
                                    np.array([c.odometry.encoder_resolution for c in configs]), rngs,
                                    rows.within("encoders"))
        believed = np.array([wheel_matrix(c.wheels, c.wheel_distance * (1 + c.odometry.wheel_distance_error))
                             for c in self.configs])
        # Least-squares inverse over the wheels each robot has (the unused column stays zero).
        self.inverse = np.zeros((n, 3, 4))
        for i, k in enumerate(self.used):
            self.inverse[i, :, :k] = np.linalg.pinv(believed[i, :k])
        self.wheel_travel = rows.hold("wheel_travel", np.zeros((n, 4)))  # measured rim travel [m]
        self.covariance = rows.hold("covariance", np.zeros((n, 3, 3)))

    @classmethod
    def stacked(cls, parts: list["OmniOdometryGroup"], rows: Rows) -> "OmniOdometryGroup":
        """The groups of copies as one on ``rows``, the whole of the rows the parts hold (see
        :mod:`pymunk_bot.robots.rows`), drawing from the same generators."""
        return cls([c for part in parts for c in part.configs],
                   np.concatenate([part.wheels for part in parts]),
                   [rng for part in parts for rng in part.rngs], rows)

    def update(self, travel: Any) -> None:
        wheels = self.encoders.measure(np.asarray(travel, dtype=float))
        self.wheel_travel += wheels
        body = np.einsum("njk,nk->nj", self.inverse, wheels)  # (dx, dy, dtheta), robot frame
        dx, dy, dtheta = body[:, 0], body[:, 1], body[:, 2]
        c, s, chord = integrate_twist(self.pose, dx, dy, dtheta)
        if self.encoders.noisy:
            self._propagate(np.array(self.encoders.noisy), c, s, chord, dx, dy, np.abs(wheels))

    def _propagate(self, i: np.ndarray, c: np.ndarray, s: np.ndarray, chord: np.ndarray,
                   dx: np.ndarray, dy: np.ndarray, abs_wheels: np.ndarray) -> None:
        """P <- F P F^T + G Q G^T, G mapping wheel noise through the inverse and the rotation."""
        m = len(i)
        f = np.tile(np.eye(3), (m, 1, 1))
        f[:, 0, 2] = -chord[i] * (dx[i] * s[i] + dy[i] * c[i])
        f[:, 1, 2] = chord[i] * (dx[i] * c[i] - dy[i] * s[i])
        rotate = np.zeros((m, 3, 3))
        rotate[:, 0, 0], rotate[:, 0, 1] = c[i], -s[i]
        rotate[:, 1, 0], rotate[:, 1, 1] = s[i], c[i]
        rotate[:, 2, 2] = 1.0
        g = rotate @ self.inverse[i]  # (m, 3, 4)
        q = self.encoders.noise_var[i, None] * abs_wheels[i]
        p = self.covariance[i]
        self.covariance[i] = f @ p @ f.transpose(0, 2, 1) + (g * q[:, None, :]) @ g.transpose(0, 2, 1)

    def handle(self, i: int) -> OdometryHandle:
        return OdometryHandle(self, i)


def of_omni_drive(group: Any, rngs: Sequence[np.random.Generator], rows: Rows = OWN) -> Any:
    """The odometry of every robot of a drive ``group`` (one generator each), its per-robot
    state on ``rows``: what ``plugins.odometry`` pairs with the drive of the same name."""
    return OmniOdometryGroup(group.configs, group.wheels, rngs, rows)
