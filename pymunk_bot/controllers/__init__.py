"""Controllers, looked up by the scenario's ``controller.type``."""
from . import avoid, go_to_goal, navigate, python, waypoints, wheels  # noqa: F401  (registers the built-ins)
from .base import Controller, LaserScan, Observation, RobotSpec, controllers, wheel_speeds

__all__ = ["Controller", "LaserScan", "Observation", "RobotSpec", "controllers", "wheel_speeds"]
