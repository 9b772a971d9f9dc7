"""`pymunk-bot map` (a scenario's static geometry as a ROS map) and `pymunk-bot generate`."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from pymunk_bot.config.errors import ScenarioError

MIN_RESOLUTION, MAX_RESOLUTION = 0.005, 1.0  # [m] per cell for `map`
MAX_MAP_CELLS = 64_000_000  # cells in a written map (as maps.ros.MAX_CELLS)


def add_parser(sub) -> None:
    """Add the `map` and `generate` subcommands to an argparse subparsers object."""
    from pymunk_bot.maps import WORLD_KINDS as KINDS

    map_cmd = sub.add_parser("map", help="write a scenario's static geometry as a ROS map "
                                         "(YAML + PGM, for Nav2's map_server)")
    map_cmd.add_argument("scenario", help="path or shipped name")
    map_cmd.add_argument("-o", "--out", type=Path, required=True, metavar="OUT.yaml",
                         help="the map YAML to write; the PGM image goes beside it")
    map_cmd.add_argument("--resolution", type=float, default=0.05,
                         help="cell size [m] (default 0.05)")
    map_cmd.set_defaults(func=cmd_map)
    gen = sub.add_parser("generate", help="write a random, solvable scenario (maze, clutter, "
                                          "office) for benchmarking controllers")
    gen.add_argument("kind", choices=KINDS, help=f"the kind of world: {', '.join(KINDS)}")
    gen.add_argument("--seed", type=int, default=0, help="the same seed gives the same file")
    gen.add_argument("-o", "--out", type=Path, required=True, metavar="WORLD.yaml",
                     help="the scenario file to write")
    gen.add_argument("--size", type=float, nargs=2, metavar=("W", "H"),
                     help="arena width and height [m] (default depends on the kind)")
    gen.set_defaults(func=cmd_generate)


def _check_out(out: Path, suffixes: tuple[str, ...]) -> None:
    if out.suffix.lower() not in suffixes:
        raise ScenarioError(str(out), "", f"the output must end in {' or '.join(suffixes)}")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise ScenarioError(str(out), "", f"directory {parent} does not exist")


def cmd_map(args: argparse.Namespace) -> int:
    from pymunk_bot.config import load_scenario
    from pymunk_bot.maps.rasterize import scenario_grid
    from pymunk_bot.maps.ros import write_ros_map

    resolution = args.resolution
    if not (math.isfinite(resolution) and MIN_RESOLUTION <= resolution <= MAX_RESOLUTION):
        raise ScenarioError("--resolution", "", f"must be between {MIN_RESOLUTION:g} and "
                                                f"{MAX_RESOLUTION:g} m (got {resolution:g})")
    _check_out(args.out, (".yaml", ".yml"))
    config = load_scenario(args.scenario)
    if config.world.size is None:  # load_scenario sizes a map world from its map
        raise ScenarioError(args.scenario, "world", "the world needs a 'size' or a 'map'")
    width, height = config.world.size
    cells = (width / resolution + 4) * (height / resolution + 4)
    if cells > MAX_MAP_CELLS:
        raise ScenarioError("--resolution", "", f"{resolution:g} m gives {cells:,.0f} cells for "
                                                f"a {width:g} x {height:g} m arena; at most "
                                                f"{MAX_MAP_CELLS:,} (use a coarser resolution)")
    grid = scenario_grid(config, resolution)
    image = write_ros_map(grid, args.out)
    print(f"wrote {args.out} and {image} ({grid.cols} x {grid.rows} cells of {resolution:g} m)")
    return 0


def cmd_generate(args: argparse.Namespace) -> int:
    from pymunk_bot.maps.generate import generate
    from pymunk_bot.outcomes.results import write_atomic

    _check_out(args.out, (".yaml", ".yml"))
    data = generate(args.kind, args.seed, tuple(args.size) if args.size else None)
    text = scenario_yaml(data)
    write_atomic(args.out, text.encode("utf-8"))
    size = data["world"]["size"]
    print(f"wrote {args.out}: {args.kind}, seed {args.seed}, {size[0]:g} x {size[1]:g} m, "
          f"{len(data['obstacles'])} obstacles")
    return 0


def scenario_yaml(data: dict) -> str:
    """A generated scenario as YAML that reads like the shipped ones: one obstacle per line."""
    import yaml

    def dump(value, flow=None) -> str:
        return yaml.safe_dump(value, sort_keys=False, default_flow_style=flow, width=100)

    head = {k: v for k, v in data.items() if k != "obstacles" and k != "robots" and k != "expect"}
    lines = [dump(head).rstrip(), "obstacles:"]
    lines += [f"  - {dump(o, True).strip()}" for o in data["obstacles"]]
    lines.append(dump({"robots": data["robots"]}).rstrip())
    lines.append(dump({"expect": data["expect"]}).rstrip())
    return "\n".join(lines) + "\n"
