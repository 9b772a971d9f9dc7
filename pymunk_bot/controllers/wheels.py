"""Constant wheel speeds (diff drive); ``velocity`` holds a body velocity on any drive."""
from __future__ import annotations

from pymunk_bot.config.controllers import WheelsControllerConfig
from pymunk_bot.controllers.base import Controller, Observation, RobotSpec


class WheelsController(Controller):
    """Drives both wheels at fixed speeds forever."""

    def __init__(self, config: WheelsControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config)
        if robot.drive != "diff":
            raise ValueError(f"wheels drives diff robots only (this one is {robot.drive}); "
                             f"use velocity")
        self._speeds = (config.left, config.right)

    observes = False  # a constant command: no observation is built for it
    constant = True  # and it is asked once

    @property
    def speeds(self) -> tuple[float, float]:
        """The wheel speeds (left, right) [m/s] it holds (fixed: give the robot another
        controller to change them)."""
        return self._speeds

    def compute(self, obs: Observation | None) -> tuple[float, float]:
        return self._speeds  # wheel speeds: the diff drive takes them as they are
