"""Sensors: each reads the world after every body has moved, at its own rate (docs/sensors.md)."""
from pymunk_bot.robots.readings import LaserScan
from pymunk_bot.sensors.bumper import Bumper, BumperReading
from pymunk_bot.sensors.imu import Imu, ImuReading
from pymunk_bot.sensors.lidar import Lidar, beam_angles
from pymunk_bot.sensors.odometry import Odometry
from pymunk_bot.sensors.schedule import Schedule

__all__ = ["Bumper", "BumperReading", "Imu", "ImuReading", "LaserScan", "Lidar", "Odometry",
           "Schedule", "beam_angles"]
