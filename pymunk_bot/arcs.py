"""The chord of a circular arc over its length, sinc(x / 2): one formula for steering the control
bodies along arcs (propulsion.py) and for dead reckoning along them (sensors/)."""
from __future__ import annotations

import math

import numpy as np


def sinc_half_scalar(x: float) -> float:
    """sin(x/2) / (x/2) for one float: the chord of an arc over its length."""
    half = 0.5 * x
    return 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half


def sinc_half(x: np.ndarray) -> np.ndarray:
    """sin(x/2) / (x/2), elementwise: the chord of an arc over its length."""
    half = 0.5 * np.asarray(x, dtype=float)
    small = np.abs(half) < 1e-4
    if not small.any():  # the same floats, without the selections
        return np.sin(half) / half
    safe = np.where(small, 1.0, half)
    return np.where(small, 1.0 - half * half / 6.0, np.sin(safe) / safe)
