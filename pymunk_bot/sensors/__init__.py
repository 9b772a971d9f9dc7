"""Sensors: each reads the world after every body has moved, at its own rate (docs/sensors.md)."""
from ..readings import LaserScan
from .bumper import Bumper, BumperReading
from .imu import Imu, ImuReading
from .lidar import Lidar, beam_angles
from .odometry import Odometry
from .schedule import Schedule

__all__ = ["Bumper", "BumperReading", "Imu", "ImuReading", "LaserScan", "Lidar", "Odometry",
           "Schedule", "beam_angles"]
