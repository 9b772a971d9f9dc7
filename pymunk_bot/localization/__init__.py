"""Localization and mapping: what turns odometry, scans and the map into the pose a controller
sees. Built in: ``ground_truth``, ``odometry`` (the default), ``mcl`` (ROS AMCL's), ``ekf``,
``slam`` (graph SLAM), and occupancy-grid ``mapping``; see docs/localization.md.

The algorithms import scipy, so they load on first use (``localizers.get`` imports them).
"""
from __future__ import annotations

import importlib
from typing import Any

from pymunk_bot.plugins import localizers
from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.config.localizer_checks import check_localizer, check_mapping
from pymunk_bot.config.localization import MAX_MAP_CELLS, MAX_PARTICLES_LIMIT, EkfConfig, MappingConfig, MclConfig, SlamConfig

_LAZY = {"MclLocalizer": "mcl", "EkfLocalizer": "ekf", "SlamLocalizer": "slam",
         "OccupancyMapper": "mapping", "ate": "metrics", "rpe": "metrics",
         "error_block": "metrics", "map_scores": "metrics", "read_tum": "tum",
         "write_tum": "tum", "TrajectoryRecorder": "tum"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["Localizer", "LocalizerContext", "LocalizerInputs", "localizers", "MclConfig",
           "EkfConfig", "SlamConfig", "MappingConfig", "MclLocalizer", "EkfLocalizer",
           "SlamLocalizer", "OccupancyMapper", "check_localizer", "check_mapping", "ate", "rpe",
           "error_block", "map_scores", "read_tum", "write_tum", "TrajectoryRecorder",
           "MAX_PARTICLES_LIMIT", "MAX_MAP_CELLS"]
