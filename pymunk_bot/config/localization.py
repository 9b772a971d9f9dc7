"""Sections of the built-in localizers (``localization: <name>`` or ``{type: <name>, ...}``)."""
from __future__ import annotations

from typing import Any, Literal

from pymunk_bot.config.types import Section


class GroundTruthLocalizerConfig(Section):
    """The controller sees the true pose (no localization error: for tests and baselines)."""

    type: Literal["ground_truth"]


class OdometryLocalizerConfig(Section):
    """The controller sees dead reckoning from the wheel encoders (drifts like a real robot's)."""

    type: Literal["odometry"]


class PythonLocalizerConfig(Section):
    """A user's own localizer class, imported from ``class_path`` ('package.module:Class'):
    a :class:`pymunk_bot.localization.Localizer` subclass built as ``Class(config, context)``."""

    type: Literal["python"]
    class_path: str
    params: dict[str, Any] = {}  # handed to the class as ``config.params``
