"""A localizer's estimate scored against the truth while the run goes (the result's
``localization`` block)."""
from __future__ import annotations

import numpy as np

from pymunk_bot.sensors.schedule import Schedule
from pymunk_bot.localization.metrics import error_block


class LocalizationScore:
    """The localizer's estimate against the truth, sampled at a fixed rate."""

    def __init__(self, rate: float) -> None:
        self.schedule = Schedule(rate)
        self.truth: list[np.ndarray] = []
        self.estimate: list[np.ndarray] = []

    def add(self, truth: np.ndarray, estimate: np.ndarray) -> None:
        """One sample: the true pose and the estimate [x, y, theta]."""
        self.truth.append(np.array(truth, dtype=float))
        self.estimate.append(np.array(estimate, dtype=float))

    def block(self) -> dict[str, float]:
        """rmse, max_error, final_error [m] of the position; heading_rmse [rad]."""
        return error_block(np.array(self.truth), np.array(self.estimate))
