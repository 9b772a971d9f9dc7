"""The ROS 2 side of the command line: ``run --log run.mcap --profile ros2``, ``run --rosbridge``
and ``convert --profile ros2``. main.py, outputs.py and foxglove.py only hook these in."""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.cli.served import ServedOutputs

PROFILES = ("foxglove", "ros2")


def add_run_options(run: argparse.ArgumentParser) -> None:
    """``--profile``, ``--rosbridge`` and ``--cmd-timeout`` on ``run`` (``--port``, ``--host``
    and ``--speed`` are shared with ``--foxglove``)."""
    from pymunk_bot.ros2.names import DEFAULT_COMMAND_TIMEOUT, DEFAULT_PORT

    group = run.add_argument_group("ROS 2 (see docs/ros2.md)")
    group.add_argument("--profile", choices=PROFILES,
                       help="with --log RUN.mcap: Foxglove's schemas (default) or a ROS 2 bag "
                            "(CDR messages that `ros2 bag play` reads)")
    group.add_argument("--rosbridge", action="store_true",
                       help=f"serve the run over the rosbridge v2 protocol (default port "
                            f"{DEFAULT_PORT}) to roslibpy, roslibjs, Foxglove or Lichtblick")
    group.add_argument("--cmd-timeout", type=float, metavar="SECONDS",
                       help=f"with --rosbridge or --foxglove: a robot driven by /cmd_vel is "
                            f"stopped and given "
                            f"back to its controller after this long without a command "
                            f"(default {DEFAULT_COMMAND_TIMEOUT:g})")


def add_convert_options(convert: argparse.ArgumentParser) -> None:
    """``--profile`` on ``convert``."""
    convert.add_argument("--profile", choices=PROFILES,
                         help="for an .mcap target: Foxglove's schemas (default) or a ROS 2 bag")


def wants_ros2_bag(args) -> bool:
    """Whether ``--profile ros2`` was asked for."""
    return getattr(args, "profile", None) == "ros2"


def _require(option: str) -> None:
    from pymunk_bot.ros2 import require

    for module in ("rosbags", "mcap"):
        require(module, option)


def convert_to_bag(source: Path, target: Path) -> int:
    """``convert SOURCE TARGET.mcap --profile ros2``: an .npz or Foxglove-profile MCAP run log
    as a ROS 2 bag."""
    _require("convert")
    if target.suffix.lower() != ".mcap":
        raise ScenarioError("--profile", "", f"ros2 writes an .mcap bag, not "
                                             f"{target.suffix or target}")
    from pymunk_bot.foxglove.reader import load_any
    from pymunk_bot.ros2.bag import write_bag

    log = load_any(source)
    messages = write_bag(log, target)
    print(f"wrote {target} (ROS 2 bag: {messages} messages, {log.time[-1]:.2f} s)")
    return 0


@dataclass
class Ros2Outputs(ServedOutputs):
    """A ROS 2 bag (``log``) and/or a rosbridge server for one run."""

    kind: str = "ROS 2 bag, "


def prepare_ros2(args, sim, log_path: Path | None) -> Ros2Outputs | None:
    """Start what ``--profile ros2`` and ``--rosbridge`` ask for; None if neither."""
    bag = wants_ros2_bag(args)
    live = getattr(args, "rosbridge", False)
    if getattr(args, "profile", None) is not None and (
            log_path is None or log_path.suffix.lower() != ".mcap"):
        raise ScenarioError("--profile", "", "only applies with --log RUN.mcap")
    if not (live or getattr(args, "foxglove", False)) and getattr(args, "cmd_timeout", None) \
            is not None:
        raise ScenarioError("--cmd-timeout", "", "only applies with --rosbridge or --foxglove")
    if live and getattr(args, "foxglove", False) and args.port is not None:
        raise ScenarioError("--port", "", "ambiguous with both --foxglove and --rosbridge; "
                                          "give one of them, or leave --port out (8765 and 9090)")
    if not (bag or live):
        return None
    _require("--rosbridge" if live else "--profile")
    if live:
        from pymunk_bot.ros2 import require

        require("websockets", "--rosbridge")
    from pymunk_bot.foxglove.frames import DEFAULT_HOST
    from pymunk_bot.foxglove.live import check_speed
    from pymunk_bot.ros2.bag import Ros2BagLogger
    from pymunk_bot.ros2.commands import CommandInbox, check_timeout
    from pymunk_bot.ros2.worldmap import world_grid
    from pymunk_bot.ros2.names import DEFAULT_COMMAND_TIMEOUT, DEFAULT_PORT

    outputs = Ros2Outputs(speed=check_speed(1.0 if args.speed is None else args.speed)
                          if live else 1.0)
    timeout = check_timeout(DEFAULT_COMMAND_TIMEOUT if args.cmd_timeout is None
                            else args.cmd_timeout)
    world_map = world_grid(sim.config)
    try:
        if live:
            from pymunk_bot.ros2.bridge import serve_sim

            outputs.server = serve_sim(sim, args.host or DEFAULT_HOST,
                                       DEFAULT_PORT if args.port is None else args.port,
                                       CommandInbox(timeout), world_map)
            print(f"rosbridge: serving the run at {outputs.server.url} (roslibpy, roslibjs, "
                  "Foxglove: Open connection -> Rosbridge)")
        if bag and log_path is not None:
            outputs.log = Ros2BagLogger(log_path, world_map).attach(sim)
    except BaseException:
        outputs.close()
        raise
    return outputs
