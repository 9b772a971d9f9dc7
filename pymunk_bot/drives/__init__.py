"""Drives, looked up by the robot's ``drive`` key (see :mod:`.base` for the seam)."""
from ..registry import Registry
from .base import DriveGroup
from .diff import DiffDrive, DiffDriveGroup, wheel_speeds

drives: Registry = Registry("drive")

__all__ = ["DiffDrive", "DiffDriveGroup", "DriveGroup", "drives", "wheel_speeds"]
