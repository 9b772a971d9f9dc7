"""Controllers, looked up by the scenario's ``controller.type``."""
from . import go_to_goal, wheels  # noqa: F401  (registers the built-in controllers)
from .base import Controller, LaserScan, Observation, RobotSpec, controllers, wheel_speeds

__all__ = ["Controller", "LaserScan", "Observation", "RobotSpec", "controllers", "wheel_speeds"]
