"""The Foxglove side of the command line: ``run --log run.mcap``, ``run --foxglove`` and
``pymunk-bot convert``. main.py and outputs.py only hook these in."""
from __future__ import annotations

import argparse
from pathlib import Path

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.cli.served import ServedOutputs

LOG_FORMATS = (".npz", ".mcap")


def add_run_options(run: argparse.ArgumentParser) -> None:
    """``--foxglove [--port] [--host] [--speed]`` on ``run``."""
    from pymunk_bot.foxglove.frames import DEFAULT_HOST, DEFAULT_PORT

    group = run.add_argument_group("live view in Foxglove")
    group.add_argument("--foxglove", action="store_true",
                       help="serve the run live to Foxglove over WebSocket (see docs/foxglove.md)")
    group.add_argument("--port", type=int,
                       help=f"WebSocket port (default {DEFAULT_PORT}, 9090 with --rosbridge; 0 picks "
                            "a free one)")
    group.add_argument("--host",
                       help=f"address to bind (default {DEFAULT_HOST}: this machine only)")
    group.add_argument("--speed", type=float,
                       help="headless pace with --foxglove or --rosbridge, x real time "
                            "(default 1.0)")


def add_parser(sub) -> None:
    """``pymunk-bot convert IN OUT``."""
    convert = sub.add_parser("convert", help="convert a run log between .npz and .mcap")
    convert.add_argument("source", type=Path, help="a run log (.npz or .mcap)")
    convert.add_argument("target", type=Path, help="the file to write (.mcap or .npz)")
    from pymunk_bot.cli.ros2 import add_convert_options

    add_convert_options(convert)  # --profile ros2
    convert.set_defaults(func=cmd_convert)


def cmd_convert(args: argparse.Namespace) -> int:
    from pymunk_bot.cli.arguments import check_output

    source, target = Path(args.source), Path(args.target)
    if source.suffix.lower() not in LOG_FORMATS:
        raise ScenarioError(str(source), "", f"unsupported file type; use {' or '.join(LOG_FORMATS)}")
    check_output("target", target, LOG_FORMATS)
    if getattr(args, "profile", None) == "ros2":
        from pymunk_bot.cli.ros2 import convert_to_bag

        return convert_to_bag(source, target)
    if target.suffix.lower() == ".mcap" or source.suffix.lower() == ".mcap":
        _require_all("convert")
    from pymunk_bot.foxglove.convert import convert

    log = convert(source, target)
    print(f"wrote {target} ({len(log.time) - 1} steps, {log.time[-1]:.2f} s)")
    return 0


def _require_all(option: str) -> None:
    from pymunk_bot.foxglove import require

    for module in ("foxglove", "mcap", "mcap_protobuf"):
        require(module, option)


class FoxgloveOutputs(ServedOutputs):
    """An MCAP log (``log``) and/or a live server for one run, fed by one publisher."""


def prepare_foxglove(args, sim, log_path: Path | None) -> FoxgloveOutputs | None:
    """Start what ``--log *.mcap`` and ``--foxglove`` ask for; None if neither."""
    live = getattr(args, "foxglove", False)
    mcap = log_path is not None and log_path.suffix.lower() == ".mcap"
    if not (live or getattr(args, "rosbridge", False)):
        for option in ("port", "host", "speed"):
            if getattr(args, option, None) is not None:
                raise ScenarioError(f"--{option}", "", "only applies with --foxglove or "
                                                       "--rosbridge")
    if not (live or mcap):
        return None
    _require_all("--foxglove" if live else "--log")
    import foxglove

    from pymunk_bot.foxglove.frames import DEFAULT_HOST, DEFAULT_PORT
    from pymunk_bot.foxglove.live import LiveServer, check_speed
    from pymunk_bot.foxglove.mcap_log import McapLogger
    from pymunk_bot.foxglove.publisher import Publisher, SimPublisher

    speed = 1.0 if args.speed is None else args.speed
    outputs = FoxgloveOutputs(speed=check_speed(speed) if live else 1.0)
    context = foxglove.Context()
    try:
        if live:
            from pymunk_bot.foxglove.teleop import attach_teleop  # /cmd_vel from Foxglove's Teleop panel

            outputs.server = LiveServer(context, args.host or DEFAULT_HOST,
                                        DEFAULT_PORT if args.port is None else args.port,
                                        teleop=attach_teleop(sim, getattr(args, "cmd_timeout", None)))
            print(f"foxglove: serving the run at {outputs.server.url} "
                  "(in Foxglove: Open connection -> Foxglove WebSocket)")
        if mcap and log_path is not None:
            outputs.log = McapLogger(log_path, context).attach(sim)  # feeds the server too
        else:
            SimPublisher(Publisher(context)).attach(sim)
    except BaseException:
        outputs.close()
        raise
    return outputs
