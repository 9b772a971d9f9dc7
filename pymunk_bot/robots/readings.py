"""Plain data passed from the simulation to controllers: what a robot knows at one instant."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np


@dataclass(frozen=True)
class RobotSpec:
    """The robot's fixed parameters, as its designer knows them."""

    name: str
    radius: float  # [m], of the disc that holds the footprint
    track_width: float  # [m]; diff drive (0 for drives without a wheel track)
    max_wheel_speed: float  # [m/s]; diff drive's per-wheel limit (others: max_speed)
    max_accel: float  # [m/s^2]
    drive: str = "diff"
    max_speed: float = math.nan  # [m/s] forward; NaN: max_wheel_speed
    max_omega: float = math.nan  # [rad/s]; NaN: a diff drive's spin rate 2 * max_wheel / track
    holonomic: bool = False  # moves sideways (omni)
    min_turn_radius: float = 0.0  # [m]; > 0 when it cannot turn on the spot (ackermann)
    # The robot's outline (a pymunk_bot.geometry.footprint.Footprint); None: a disc of ``radius``.
    footprint: Any = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if math.isnan(self.max_speed):
            object.__setattr__(self, "max_speed", self.max_wheel_speed)
        if math.isnan(self.max_omega):
            omega = 2.0 * self.max_wheel_speed / self.track_width if self.track_width > 0 else math.inf
            object.__setattr__(self, "max_omega", omega)


@dataclass(frozen=True)
class LaserScan:
    """One LiDAR measurement: ranges [m] at beam angles relative to the robot heading [rad]."""

    ranges: np.ndarray
    angles: np.ndarray
    min_range: float
    max_range: float
    offset: tuple[float, float, float]  # sensor mounting pose in the robot frame
    time: float  # when it was taken [s]


class Observation:
    """Everything a controller may use at one control tick.

    ``extra`` (further sensors' readings by name, e.g. "imu", "bumper") and ``bumper`` are built
    on first access: most controllers never read them.
    """

    __slots__ = ("time", "pose", "odometry", "goal", "goal_tolerance", "robot", "scan",
                 "_extra", "_read_extra", "localized", "explore_heading")

    def __init__(self, time: float, pose: np.ndarray, odometry: np.ndarray,
                 goal: tuple[float, float] | None, goal_tolerance: float, robot: RobotSpec,
                 scan: LaserScan | None = None, extra: dict[str, Any] | None = None,
                 read_extra: Callable[[], dict[str, Any]] | None = None,
                 localized: bool = True, explore_heading: float | None = None) -> None:
        self.time = time  # simulated time [s]
        self.pose = pose  # the localizer's estimate [x, y, theta] (odometry by default)
        self.odometry = odometry  # odometry estimate [x, y, theta]
        self.goal = goal  # [m]
        self.goal_tolerance = goal_tolerance  # [m]
        self.robot = robot
        self.scan = scan
        self._extra = extra
        self._read_extra = read_extra
        self.localized = localized  # False: the estimate is not yet trustworthy (Localizer.localized)
        # [rad, robot frame] while not localized, where driving would tell the localizer's
        # hypotheses apart (MCL's active localization); None: no preference
        self.explore_heading = explore_heading

    @property
    def extra(self) -> dict[str, Any]:
        """Readings of the further sensors, by name ("imu", "bumper", ...)."""
        if self._extra is None:
            self._extra = self._read_extra() if self._read_extra is not None else {}
        return self._extra

    @property
    def bumper(self) -> bool:
        """Touching something now."""
        reading = self.extra.get("bumper")
        return bool(reading is not None and reading.touching)
