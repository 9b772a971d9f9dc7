"""Motion along circular arcs, compiled: one formula for steering the control bodies along arcs
(:mod:`pymunk_bot.physics.steering`) and for dead reckoning along them (every drive's odometry).

No ``fastmath``: IEEE arithmetic in the order written, and ``math.sin``/``math.cos`` from the C
library, as Python's own, so one robot and rows of robots get the same floats.
"""
from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def sinc_half(x: float) -> float:
    """sin(x/2) / (x/2): the chord of an arc over its length."""
    half = 0.5 * x
    return 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half


@numba.njit(cache=True)
def arc_step(pose: np.ndarray, i: int, dx: float, dy: float,
             dtheta: float) -> tuple[float, float, float]:
    """Move pose row ``i`` [m, m, rad] in place by body-frame increments (dx, dy [m], dtheta
    [rad]) along an exact arc; returns the mid-step heading's cos and sin and the chord factor
    sinc(dtheta / 2), for covariance propagation."""
    factor = sinc_half(dtheta)
    heading = pose[i, 2] + 0.5 * dtheta
    c, s = math.cos(heading), math.sin(heading)
    pose[i, 0] += factor * (dx * c - dy * s)
    pose[i, 1] += factor * (dx * s + dy * c)
    pose[i, 2] += dtheta
    return c, s, factor


@numba.njit(cache=True)
def integrate_arcs(pose: np.ndarray, dx: np.ndarray, dy: np.ndarray, dtheta: np.ndarray,
                   cos_mid: np.ndarray, sin_mid: np.ndarray, chord: np.ndarray) -> None:
    """:func:`arc_step` for every row of ``pose`` (n, 3), the increments each (n,); fills the
    mid-step cos and sin and the chord factors (each (n,))."""
    for i in range(pose.shape[0]):
        cos_mid[i], sin_mid[i], chord[i] = arc_step(pose, i, dx[i], dy[i], dtheta[i])
