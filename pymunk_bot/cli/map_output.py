"""`pymunk-bot run ... --map-out OUT.yaml [--map-robot NAME]`: save the map a robot built.

A robot builds an occupancy grid when its scenario gives it ``mapping:`` or ``localization:
slam`` (``robot.mapper``). The output path and the robot are checked before the run, so a typo
costs no simulation time; the ROS map (YAML + PGM beside it) is written atomically after it.
"""
from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from pathlib import Path

from pymunk_bot.config.errors import ScenarioError

MAP_FORMATS = (".yaml", ".yml")


def add_run_options(run: argparse.ArgumentParser) -> None:
    """Add --map-out and --map-robot to the `run` subcommand."""
    run.add_argument("--map-out", type=Path, metavar="OUT.yaml",
                     help="save the occupancy grid a robot with `mapping` (or `slam`) built, "
                          "as a ROS map (OUT.yaml + OUT.pgm)")
    run.add_argument("--map-robot", metavar="NAME",
                     help="the robot whose map --map-out saves (default: the first that maps)")


@dataclass(frozen=True)
class MapOutput:
    """Where to save which robot's map once the run is over."""

    path: Path  # the map YAML; the PGM image goes beside it
    robot: str

    def save(self, sim) -> Path:
        """Write the robot's map as it is now; returns the YAML path."""
        from pymunk_bot.maps.ros import write_ros_map

        grid = sim.robots[self.robot].mapper.grid
        image = write_ros_map(grid, self.path)
        print(f"wrote {self.path} and {image.name} ({self.robot}'s map, {grid.cols} x "
              f"{grid.rows} cells at {grid.resolution:g} m)")
        return self.path


def _check_path(path: Path) -> Path:
    if path.suffix.lower() not in MAP_FORMATS:
        got = f"'{path.suffix}'" if path.suffix else "no extension"
        raise ScenarioError("--map-out", "", f"{path}: unsupported file type ({got}); use "
                                             f"{' or '.join(MAP_FORMATS)} (the .pgm goes beside it)")
    parent = path.parent if str(path.parent) else Path(".")
    for target in (path, path.with_suffix(".pgm")):
        if target.is_dir():
            raise ScenarioError("--map-out", "", f"{target} is a directory")
    if not parent.is_dir():
        raise ScenarioError("--map-out", "", f"{path}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise ScenarioError("--map-out", "", f"{path}: directory {parent} is not writable")
    return path


def prepare_map_output(args: argparse.Namespace, sim) -> MapOutput | None:
    """Check --map-out / --map-robot against ``sim`` before the run (ScenarioError: exit 2)."""
    path = getattr(args, "map_out", None)
    name = getattr(args, "map_robot", None)
    if path is None:
        if name is not None:
            raise ScenarioError("--map-robot", "", "only applies with --map-out")
        return None
    path = _check_path(Path(path))
    mapping = [n for n, r in sim.robots.items() if getattr(r, "mapper", None) is not None]
    if not mapping:
        raise ScenarioError("--map-out", "", "no robot builds a map in this scenario (give one "
                                             "`mapping: {resolution: 0.05}` or "
                                             "`localization: slam`)")
    if name is None:
        return MapOutput(path, mapping[0])
    if name not in sim.robots:
        raise ScenarioError("--map-robot", "", f"no robot named '{name}' (robots: "
                                               f"{', '.join(sim.robots)})")
    if name not in mapping:
        raise ScenarioError("--map-robot", "", f"robot '{name}' builds no map (robots that do: "
                                               f"{', '.join(mapping)})")
    return MapOutput(path, name)
