"""A constant body velocity, on any drive."""
from __future__ import annotations

from pymunk_bot.config.controllers import VelocityControllerConfig
from pymunk_bot.controllers.base import Command, Controller, Observation, RobotSpec


class VelocityController(Controller):
    """Holds (v, omega, vy) forever; the drive limits it to what the robot can do."""

    def __init__(self, config: VelocityControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config)
        self._command = Command(config.v, config.omega, config.vy)

    observes = False  # a constant command: no observation is built for it
    constant = True  # and it is asked once

    @property
    def command(self) -> Command:
        """The body velocity it holds (fixed: give the robot another controller to change it)."""
        return self._command

    def compute(self, obs: Observation | None) -> Command:
        return self._command
