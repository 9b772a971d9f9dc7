"""Drives, looked up by the robot's ``drive`` key (see :mod:`.base` for the seam)."""
from pymunk_bot.config.registry import Registry
from pymunk_bot.robots.drives.base import DriveGroup
from pymunk_bot.robots.drives.diff import DiffDrive, DiffDriveGroup, wheel_speeds

drives: Registry = Registry("drive")

__all__ = ["DiffDrive", "DiffDriveGroup", "DriveGroup", "drives", "wheel_speeds"]
