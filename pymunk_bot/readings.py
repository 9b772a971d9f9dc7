"""Plain data passed from the simulation to controllers: what a robot knows at one instant."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class RobotSpec:
    """The robot's fixed parameters, as its designer knows them."""

    name: str
    radius: float  # [m]
    track_width: float  # [m]
    max_wheel_speed: float  # [m/s]
    max_accel: float  # [m/s^2]


@dataclass(frozen=True)
class LaserScan:
    """One LiDAR measurement: ranges [m] at beam angles relative to the robot heading [rad]."""

    ranges: np.ndarray
    angles: np.ndarray
    min_range: float
    max_range: float
    offset: tuple[float, float, float]  # sensor mounting pose in the robot frame
    time: float  # when it was taken [s]


@dataclass(frozen=True)
class Observation:
    """Everything a controller may use at one control tick."""

    time: float  # simulated time [s]
    pose: np.ndarray  # pose estimate [x, y, theta]: odometry, or ground truth if configured
    odometry: np.ndarray  # odometry estimate [x, y, theta]
    goal: tuple[float, float] | None  # [m]
    goal_tolerance: float  # [m]
    robot: RobotSpec
    scan: LaserScan | None = None
    bumper: bool = False  # touching something now
    extra: dict[str, Any] = field(default_factory=dict)  # further sensors (e.g. "imu")
