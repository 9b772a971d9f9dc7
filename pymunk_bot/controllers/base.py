"""What a controller sees and what it returns.

A controller is called at its own ``rate`` with an :class:`Observation` (the robot's sensor
readings and its pose estimate, never ground truth unless the scenario asks for it) and returns
wheel speeds. Write your own by subclassing :class:`Controller`.
"""
from __future__ import annotations

from ..readings import LaserScan, Observation, RobotSpec
from ..registry import Registry

__all__ = ["Controller", "LaserScan", "Observation", "RobotSpec", "controllers", "wheel_speeds"]


class Controller:
    """Base class for controllers: override :meth:`compute`.

    ``status`` is "running", "arrived" (goal reached as far as the controller knows) or
    "failed" (it gave up, e.g. no path); ``message`` says why.
    """

    rate: float = 10.0  # [Hz]
    needs_map: bool = False  # True: the simulation calls set_map() before the first compute()

    def __init__(self, config=None, robot: RobotSpec | None = None) -> None:
        """Built-in controllers pass their config and robot: that sets ``config``, ``rate`` and
        ``max_speed`` (the config's, capped by the robot's max wheel speed)."""
        self.status = "running"
        self.message = ""
        if config is not None:
            self.config = config
            self.rate = getattr(config, "rate", None) or self.rate
        if robot is not None:
            wanted = getattr(config, "max_speed", None) or robot.max_wheel_speed
            self.max_speed = min(wanted, robot.max_wheel_speed)

    def compute(self, obs: Observation) -> tuple[float, float]:
        """Left and right wheel speeds [m/s] for the next control period."""
        raise NotImplementedError

    def set_map(self, world_map) -> None:
        """Receive the scenario's map (a :class:`pymunk_bot.planning.MapInfo`) if ``needs_map``."""
        self.map = world_map

    def debug_path(self) -> list[tuple[float, float]] | None:
        """A path the controller is following, for views (None if it has none)."""
        return None


controllers: Registry[type] = Registry("controller")


def wheel_speeds(v: float, omega: float, track_width: float) -> tuple[float, float]:
    """(v, omega) -> (left, right) wheel speeds."""
    half = 0.5 * omega * track_width
    return v - half, v + half
