"""Localizers: what turns odometry, scans and the map into the pose a controller sees."""
from ..plugins import localizers
from .base import Localizer, LocalizerContext, LocalizerInputs

__all__ = ["Localizer", "LocalizerContext", "LocalizerInputs", "localizers"]
