"""The `pymunk-bot` command line: the parser, `run`, `validate`, `list`, `plot`, `replay`, `bench`."""
from __future__ import annotations

import argparse
import datetime  # noqa: F401  (now: pydantic-core imports it at start-up, and a Ctrl-C landing
# inside that import makes its Rust code panic with a backtrace)
import math
import os
import signal
import subprocess
import sys
import time
import traceback
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

from pymunk_bot.cli.bench import SECTION_NAMES, cmd_bench
from pymunk_bot.config.errors import ControllerError, ScenarioError, ScenarioWarning
from pymunk_bot.cli.arguments import EXIT_BAD_INPUT, EXIT_EXPECTATION_FAILED, EXIT_INTERNAL_ERROR, EXIT_OK, \
    Parser, duration_seconds, seed_number

if TYPE_CHECKING:
    from pymunk_bot.cli.compiling import CompileWatch

DESCRIPTION = ("pymunk-bot: a 2D mobile-robot simulator on pymunk. Run, check and test "
               "scenarios, sweep their parameters, plot and replay run logs, and convert maps.")


def _display_available() -> bool:
    if os.environ.get("SDL_VIDEODRIVER") in ("dummy", "offscreen"):
        return False
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")) or sys.platform in (
        "win32", "darwin")


def _cmd_run(args: argparse.Namespace) -> int:
    from pymunk_bot.config import load_scenario
    from pymunk_bot.outcomes.results import writable_problem
    from pymunk_bot.engine.simulation import Simulation

    if args.out is not None and (problem := writable_problem(args.out)) is not None:
        raise ScenarioError("--out", "", problem)  # before anything runs
    from pymunk_bot.cli.sweep import parse_settings, scenario_with_settings, settings_echo

    settings = parse_settings(args.assignments, one_value=True)  # before loading anything
    config = load_scenario(args.scenario)
    if settings:
        loaded, config = config, scenario_with_settings(config, args.scenario, settings)
        for line in settings_echo(loaded, config, settings):  # stderr: stdout is the report
            print(line, file=sys.stderr)
    from pymunk_bot.cli.compiling import CompileWatch

    with CompileWatch() as compiling:  # the first run after installing compiles numba's kernels
        sim = Simulation(config, seed=args.seed, source=args.scenario)
        sim.attach(_interrupts.raise_if_seen)  # a signal that a C callback swallowed stops it
        sim.attach(compiling)  # ticks that compiled are left out of the real-time factor
        duration = args.duration if args.duration is not None else config.world.duration
        from pymunk_bot.cli.outputs import prepare_outputs

        outputs = prepare_outputs(args, sim)  # checks --record/--log paths first, starts the log
        compiling.release()  # the input was good: now say if numba compiles
        try:
            return _run_with_outputs(args, sim, duration, outputs, compiling)
        finally:
            outputs.close()  # an unfinished MCAP is removed, a live server stopped


def _run_with_outputs(args: argparse.Namespace, sim, duration: float, outputs,
                      compiling: CompileWatch) -> int:
    from pymunk_bot.outcomes.results import write_json

    interactive = not args.headless and outputs.record is None and _display_available()
    watched: float | None = None
    if interactive:
        from pymunk_bot.viewer import ViewerUnavailable, run_window

        opened = time.perf_counter()
        try:
            run_window(sim, duration)
            watched = time.perf_counter() - opened  # [s] of real time the window was open
        except ViewerUnavailable as exc:
            interactive = False
            print(f"note: the window cannot open ({exc}); running headless")
    if outputs.record is not None:
        outputs.record_run(sim, duration)  # offscreen: runs exactly `duration`, like headless
    elif not interactive:
        if not args.headless and not _display_available():
            print("note: no display found; running headless (pass --headless to silence this)")
        outputs.run_headless(sim, duration)
    compiling.report()  # after a first run: how long numba compiled
    result = sim.result()
    verdict = sim.verdict()
    unwritten = None
    if args.out:  # first: the result survives a disk that the logs below fill
        try:
            write_json(args.out, result)
        except OSError:
            unwritten = args.out  # again below: a log that filled the disk is then removed
    failed = outputs.finish(sim)  # the run log, the built map (--map-out), trajectories
    if unwritten is not None:
        try:
            write_json(unwritten, result)
        except OSError as exc:
            failed.insert(0, exc)
    _print_summary(result, verdict.lines(), watched)
    for problem in failed:  # after the verdict, so the last line says what was lost
        print(f"error: {write_failure(problem)}", file=sys.stderr)
    if failed:
        return EXIT_BAD_INPUT  # the run is told, but a file asked for is missing
    return EXIT_OK if verdict.passed else EXIT_EXPECTATION_FAILED


def write_failure(exc: OSError) -> str:
    """``FILE: problem`` for an output that could not be written (a full disk)."""
    where = f"{exc.filename}: " if exc.filename else ""
    return f"{where}{exc.strerror or exc} (not written)"


def _print_summary(result: dict, verdict_lines: list[str], watched: float | None = None) -> None:
    """The run's result; ``watched`` [s]: how long the window was open, if there was one."""
    from pymunk_bot.geometry.plane import wrap_angle

    print(summary_line(result, watched))
    for name, r in result["robots"].items():
        goal = ""
        if r["goal_reached"]:
            goal = f", goal reached at {r['time_to_goal']:.2f} s"
        x, y, turned = r["pose"]
        theta = wrap_angle(turned)  # where it points; the JSON keeps the turns (unwrapped)
        status = r.get("controller_status")
        controller = f", controller {status}" if status not in (None, "failed") else ""
        if status == "failed" and not any(f"{name}: controller failed" in line
                                          for line in verdict_lines):
            controller = f", controller failed as expected: {r['controller_message']}"
        print(f"  {name}: pose ({x:.3f}, {y:.3f}, {theta:.3f}), {r['distance']:.2f} m travelled, "
              f"{r['collisions']} collision(s){goal}{controller}")
    for line in verdict_lines[:-1]:
        print(f"  {line}")
    print(verdict_lines[-1])


def summary_line(result: dict, watched: float | None = None) -> str:
    """What was simulated and what was measured: the real time spent computing steps (the
    result's ``wall_time``; its ratio is ``real_time_factor``), and, after a window, how long
    the run was watched, which is what its speed setting paced."""
    rtf = result["real_time_factor"]
    line = f"{result['scenario']} (seed {result['seed']}): {result['sim_time']:.2f} s simulated"
    compute = f"computing the steps took {result['wall_time']:.3f} s"
    if watched is None:
        return f"{line}; {compute}" + (f" ({rtf:.0f}x real time)" if rtf else "")
    pace = f" ({result['sim_time'] / watched:.2f}x real time)" if watched > 0 else ""
    headless = f" (headless, it would run at {rtf:.0f}x real time)" if rtf else ""
    return f"{line}, watched over {watched:.1f} s in the window{pace}; {compute} of that{headless}"


def _cmd_validate(args: argparse.Namespace) -> int:
    from pymunk_bot.config import load_scenario

    status = EXIT_OK
    for spec in args.scenarios:
        try:
            config = load_scenario(spec)
        except ScenarioError as exc:
            print(f"error: {exc}", file=sys.stderr)
            status = EXIT_BAD_INPUT
        else:
            print(f"ok: {spec} ({config.name})")
    return status


def _cmd_list(args: argparse.Namespace) -> int:
    from pymunk_bot.config import load_scenario, shipped_scenarios

    for name, path in shipped_scenarios().items():
        try:
            description = load_scenario(path).description
        except ScenarioError as exc:
            description = f"(invalid: {exc})"
        print(f"{name:<22} {description}")
    return EXIT_OK


def _cmd_plot(args: argparse.Namespace) -> int:
    from pymunk_bot.cli.outputs import cmd_plot

    return cmd_plot(args)


def _cmd_replay(args: argparse.Namespace) -> int:
    from pymunk_bot.cli.outputs import cmd_replay

    return cmd_replay(args, _display_available())


def _frame_size(text: str) -> tuple[int, int]:
    from pymunk_bot.cli.outputs import parse_size

    try:
        return parse_size(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _add_video_options(parser: argparse.ArgumentParser, record_help: str) -> None:
    parser.add_argument("--record", type=Path, metavar="VIDEO", help=record_help)
    parser.add_argument("--fps", type=float, help="video frames per second (default: 30 for "
                                                  ".mp4, 10 for .gif)")
    parser.add_argument("--size", type=_frame_size, metavar="WxH",
                        help="video frame size in pixels (default: fitted to the arena)")


def build_parser() -> argparse.ArgumentParser:
    from pymunk_bot import __version__

    parser = Parser(prog="pymunk-bot", description=DESCRIPTION,
                    epilog="`pymunk-bot COMMAND --help` describes each command; docs/cli.md "
                           "has them all.")
    parser.add_argument("--version", action="version", version=f"pymunk-bot {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    run = sub.add_parser("run", help="run a scenario (window if a display is available)")
    run.add_argument("scenario", nargs="?", help="path or shipped name (default: built-in)")
    run.add_argument("--headless", action="store_true", help="no window, full speed")
    run.add_argument("--duration", type=duration_seconds,
                     help="simulated seconds (default: the scenario's)")
    run.add_argument("--seed", type=seed_number, help="override the scenario's seed (an integer >= 0)")
    run.add_argument("--out", type=Path, help="write the JSON result here (atomically)")
    run.add_argument("--set", dest="assignments", action="append", default=[],
                     metavar="KEY.PATH=VALUE",
                     help="change one scenario value for this run, e.g. "
                          "robots[0].max_wheel_speed=0.8 (repeatable; the key paths and checks "
                          "of sweep --set)")
    _add_video_options(run, "render the run offscreen to a video (.mp4 or .gif); no window")
    run.add_argument("--log", type=Path, metavar="RUN.npz|RUN.mcap",
                     help="save poses, odometry, commands and LiDAR scans over time (.mcap: "
                          "Foxglove schemas, see docs/foxglove.md)")
    from pymunk_bot.cli.foxglove import add_parser as add_convert_parser, add_run_options

    add_run_options(run)  # --foxglove --port --host --speed
    from pymunk_bot.cli.ros2 import add_run_options as add_ros2_options

    add_ros2_options(run)  # --profile --rosbridge --cmd-timeout
    from pymunk_bot.cli.map_output import add_run_options as add_map_options

    add_map_options(run)  # --map-out --map-robot
    from pymunk_bot.cli.trajectory import add_run_options as add_trajectory_options

    add_trajectory_options(run)  # --trajectory-out
    run.set_defaults(func=_cmd_run)
    plot = sub.add_parser("plot", help="plot a run log (trajectories, speed, LiDAR ranges)")
    plot.add_argument("log", type=Path, help="a run log written by `run --log`")
    plot.add_argument("-o", "--output", type=Path,
                      help="image file (.png, .pdf, .svg; default: next to the log)")
    plot.add_argument("--kind", choices=("all", "map", "speed", "ranges", "localization"),
                      default="all",
                      help="which figure (default: all)")
    plot.add_argument("--robot", help="only this robot (default: all robots)")
    plot.set_defaults(func=_cmd_plot)
    replay = sub.add_parser("replay", help="play a run log in the window (or to a video)")
    replay.add_argument("log", type=Path, help="a run log written by `run --log`")
    _add_video_options(replay, "render the replay to a video (.mp4 or .gif) instead")
    replay.set_defaults(func=_cmd_replay)
    validate = sub.add_parser("validate", help="check scenario files")
    validate.add_argument("scenarios", nargs="+", help="scenario files or shipped names; "
                                                        "each gets `ok: FILE` or one error line")
    validate.set_defaults(func=_cmd_validate)
    listing = sub.add_parser("list", help="list shipped scenarios")
    listing.set_defaults(func=_cmd_list)
    bench = sub.add_parser("bench", help="run the benchmarks: speed against bare pymunk, "
                                         "contacts, localization, fuzzing (see --only)")
    bench.add_argument("--quick", action="store_true", help="fewer repeats")
    bench.add_argument("--only", action="append", choices=SECTION_NAMES, metavar="NAME",
                       help=f"run only this section (repeatable): {', '.join(SECTION_NAMES)}")
    bench.set_defaults(func=cmd_bench)
    from pymunk_bot.cli.test import add_parser as add_test_parser  # `pymunk-bot test`

    add_test_parser(sub)
    add_convert_parser(sub)  # `pymunk-bot convert`
    from pymunk_bot.cli.maps import add_parser as add_map_parsers  # `pymunk-bot map`, `generate`

    add_map_parsers(sub)
    from pymunk_bot.cli.benchmark import add_parser as add_benchmark_parser  # `pymunk-bot benchmark`

    add_benchmark_parser(sub)
    from pymunk_bot.cli.sweep import add_parser as add_sweep_parser  # `pymunk-bot sweep`

    add_sweep_parser(sub)
    from pymunk_bot.cli.evaluate import add_parser as add_evaluate_parser  # `pymunk-bot evaluate`

    add_evaluate_parser(sub)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Scenario warnings as one line on stderr; others as Python prints them."""
    if issubclass(category, ScenarioWarning):
        print(f"warning: {message}", file=sys.stderr)
    else:
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


class _Interrupts:
    """Ctrl-C (raised as KeyboardInterrupt, as by default) and SIGTERM (raised as
    ``SystemExit(128 + signum)``, so ``finally`` blocks run and no .part file is left behind),
    each remembered.

    Raised inside a callback from C (numba's compiler, a pymunk collision handler) the exception
    is "ignored" there; inside a compiled extension's initialisation (pydantic-core's) it can come
    out as another exception. Remembering it lets ``main`` raise it again at the next safe point
    (after every tick, and when the command returns) and report the second case as what it was.
    """

    def __init__(self) -> None:
        self.seen = False  # a Ctrl-C
        self.terminated: int | None = None  # the exit status a SIGTERM asked for

    def reset(self) -> None:
        """Forget earlier signals (``main`` may be called again in one process: tests)."""
        self.seen = False
        self.terminated = None

    def __call__(self, signum, frame) -> None:
        self.seen = True
        raise KeyboardInterrupt

    def terminate(self, signum, frame) -> None:
        """The SIGTERM handler."""
        self.terminated = 128 + signum
        raise SystemExit(self.terminated)

    def raise_if_seen(self, sim: object = None) -> None:
        """Raise the signal's exception that a C callback swallowed (a ``Simulation`` observer
        too)."""
        if self.terminated is not None:
            raise SystemExit(self.terminated)
        if self.seen:
            raise KeyboardInterrupt

    def unraisable_hook(self, previous):
        """A ``sys.unraisablehook``: a signal's exception swallowed by a C callback is
        remembered, not printed with a traceback; everything else goes to ``previous``."""
        def hook(info) -> None:
            if info.exc_type is not None and issubclass(info.exc_type, KeyboardInterrupt):
                self.seen = True
                return
            if (info.exc_type is not None and issubclass(info.exc_type, SystemExit)
                    and self.terminated is not None):
                return  # remembered by terminate: raised again at the next safe point
            previous(info)

        return hook


_interrupts = _Interrupts()


def main(argv: list[str] | None = None) -> int:
    """The `pymunk-bot` entry point; returns the exit status (see docs/cli.md)."""
    previous = None
    _interrupts.reset()
    try:
        previous = signal.signal(signal.SIGTERM, _interrupts.terminate)
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not if ignored
            signal.signal(signal.SIGINT, _interrupts)
    except ValueError:  # not the main thread: leave signals alone
        pass
    unraisable = sys.unraisablehook
    sys.unraisablehook = _interrupts.unraisable_hook(unraisable)
    try:  # the parser too: building it imports most of pymunk-bot (Ctrl-C may come then)
        args = build_parser().parse_args(argv)
        with warnings.catch_warnings():
            warnings.simplefilter("always", ScenarioWarning)
            warnings.showwarning = _show_warning
            status = args.func(args)
        _interrupts.raise_if_seen()
        return status
    except ScenarioError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ControllerError as exc:
        traceback.print_exception(exc.__cause__ or exc, file=sys.stderr)
        print(f"error: controller {exc} (a bug in the controller's code, not in the scenario)",
              file=sys.stderr)
        return EXIT_EXPECTATION_FAILED
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `pymunk-bot run ... | head -1`: the reader left, nothing to say
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # Python's flush at exit must not fail again
        return 128 + signal.SIGPIPE
    except BaseException as exc:  # what an interrupt became, or a bug in pymunk-bot itself
        if _interrupts.seen and not isinstance(exc, SystemExit):
            print("interrupted", file=sys.stderr)
            return 130
        if not isinstance(exc, Exception):
            raise
        traceback.print_exc(file=sys.stderr)
        print(f"internal error: {type(exc).__name__}: {exc} (this is a bug in pymunk-bot; "
              "please report it with the traceback above)", file=sys.stderr)
        return EXIT_INTERNAL_ERROR
    finally:
        sys.unraisablehook = unraisable
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
        if signal.getsignal(signal.SIGINT) is _interrupts:
            signal.signal(signal.SIGINT, signal.default_int_handler)


if __name__ == "__main__":
    sys.exit(main())
