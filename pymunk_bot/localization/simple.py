"""The two localizers every robot can have: the truth, and dead reckoning. Both are passive:
they read their source when asked, so the simulation skips their per-tick update."""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs


class GroundTruthLocalizer(Localizer):
    """Reports the true pose (zero covariance): for tests and as a baseline."""

    passive = True

    def __init__(self, config: Any, context: LocalizerContext,
                 truth: Callable[[], np.ndarray] | None = None) -> None:
        super().__init__(config, context)
        self._truth = truth  # () -> the true pose; the build hands it in

    @property
    def pose(self) -> np.ndarray:
        return self._truth() if self._truth is not None else self._pose

    @pose.setter
    def pose(self, value: np.ndarray) -> None:
        self._pose = np.asarray(value, dtype=float)

    def update(self, inputs: LocalizerInputs) -> None:
        """Nothing to fold in: the pose is read from the world when asked."""


class OdometryLocalizer(Localizer):
    """Reports the odometry estimate and the covariance its noise model predicts."""

    passive = True

    def __init__(self, config: Any, context: LocalizerContext, odometry: Any = None) -> None:
        super().__init__(config, context)
        self._odometry = odometry
        self.reports_odometry = odometry is not None

    @property
    def pose(self) -> np.ndarray:
        return self._odometry.pose if self._odometry is not None else self._pose

    @pose.setter
    def pose(self, value: np.ndarray) -> None:
        self._pose = np.asarray(value, dtype=float)

    @property
    def covariance(self) -> np.ndarray:
        return self._odometry.covariance if self._odometry is not None else self._covariance

    @covariance.setter
    def covariance(self, value: np.ndarray) -> None:
        self._covariance = np.asarray(value, dtype=float)

    def update(self, inputs: LocalizerInputs) -> None:
        """Nothing to fold in: the pose is the odometry's, read when asked."""
