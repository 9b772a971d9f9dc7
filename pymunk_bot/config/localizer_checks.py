"""Checks that a localizer or a mapping section can run on its robot (called while validating)."""
from __future__ import annotations

from typing import Any

from pymunk_bot.plugins import localizers
from pymunk_bot.config.localization import LOCALIZER_MAP_RESOLUTION, MAX_MAP_CELLS, MappingConfig

MIN_MATCH_BEAMS = 10  # ekf and slam match scans: fewer beams cannot fix a pose


def check_localizer(config: Any, robot_config: Any, has_map: bool = True,
                    arena: tuple[float, float] | None = None) -> None:
    """Refuse a localizer the robot cannot run: ValueError with a one-line reason.

    ``config`` is a localizer config model (its ``type`` names the registry entry),
    ``robot_config`` the robot's RobotConfig, ``has_map`` whether a map will be given,
    ``arena`` its width and height [m] (the map it is given is bounded in cells).
    """
    name = getattr(config, "type", None)
    if not isinstance(name, str) or name not in localizers:
        return  # ground_truth / odometry / python: nothing of ours to check
    cls = localizers.get(name)
    lidar = getattr(robot_config, "lidar", None)
    if getattr(cls, "needs_lidar", False) and lidar is None:
        raise ValueError(f"{name} needs a LiDAR: add a lidar section to this robot")
    if getattr(cls, "needs_map", False) and not has_map:
        raise ValueError(f"{name} needs a map: give world.map, or use slam to build one")
    if getattr(cls, "needs_map", False) and arena is not None:
        r = LOCALIZER_MAP_RESOLUTION
        cells = (arena[0] / r) * (arena[1] / r)
        if cells > MAX_MAP_CELLS:
            raise ValueError(f"{name} is given the arena's map at {r:g} m: a {arena[0]:g} x "
                             f"{arena[1]:g} m arena needs {cells:.3g} cells, over the limit of "
                             f"{MAX_MAP_CELLS}; use a smaller arena")
    if name in ("ekf", "slam") and lidar is not None and lidar.beams < MIN_MATCH_BEAMS:
        raise ValueError(f"{name} matches scans and needs a LiDAR with at least "
                         f"{MIN_MATCH_BEAMS} beams (got {lidar.beams})")


def check_mapping(config: MappingConfig, arena: tuple[float, float]) -> None:
    """Refuse a map too large for memory: ValueError naming the limit."""
    m, r = config.margin, config.resolution
    cells = ((arena[0] + 2 * m) / r) * ((arena[1] + 2 * m) / r)
    if cells > MAX_MAP_CELLS:
        raise ValueError(f"a {arena[0]:g} x {arena[1]:g} m arena at resolution {r:g} m needs "
                         f"{cells:.3g} cells, over the limit of {MAX_MAP_CELLS}; use a coarser "
                         "resolution")
