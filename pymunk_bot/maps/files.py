"""Map files by extension: a ROS map_server YAML (.yaml, .yml) or an SVG floor plan (.svg)."""
from __future__ import annotations

from pathlib import Path

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.maps.outlines import MapGeometry, geometry_from_grid
from pymunk_bot.maps.ros import read_ros_map
from pymunk_bot.maps.svg import read_svg_map

SUFFIXES = (".yaml", ".yml", ".svg")


def load_world_map(path: str | Path, map_scale: float | None = None, source: str | None = None,
                   key_path: str = "world.map") -> MapGeometry:
    """The static geometry of a map file, chosen by its extension.

    ``map_scale`` (metres per SVG user unit) applies to SVG plans only. ``source`` and
    ``key_path`` name where the map was referenced, for the one-line errors; resolve a
    relative path against the scenario file's directory before calling.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml"):
        if map_scale is not None:
            raise ScenarioError(source or str(path), "world.map_scale",
                                "applies to SVG maps only (a ROS map has its own resolution)")
        return geometry_from_grid(read_ros_map(path, source, key_path))
    if suffix == ".svg":
        return read_svg_map(path, map_scale, source, key_path)
    raise ScenarioError(source or str(path), key_path if source else "",
                        f"{path}: unknown map format '{path.suffix}' (use {', '.join(SUFFIXES)})")
