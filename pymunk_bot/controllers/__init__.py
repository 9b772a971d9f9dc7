"""Controllers, looked up by the scenario's ``controller.type`` (see :mod:`pymunk_bot.plugins`)."""
from pymunk_bot.controllers.base import STOP, Command, Controller, LaserScan, Observation, RobotSpec, controllers, wheel_speeds

__all__ = ["STOP", "Command", "Controller", "LaserScan", "Observation", "RobotSpec", "controllers",
           "wheel_speeds"]
