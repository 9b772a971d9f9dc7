"""`pymunk-bot sweep`: a grid of scenario values times seeds, on a chosen backend."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pymunk_bot.config.errors import ScenarioError

if TYPE_CHECKING:
    from pymunk_bot.config import ScenarioConfig

EXIT_OK, EXIT_SOME_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 3


def add_parser(subparsers) -> argparse.ArgumentParser:
    from pymunk_bot.sweep import BACKENDS

    sweep = subparsers.add_parser(
        "sweep", help="run a scenario over a grid of parameter values and seeds",
        description="Run SCENARIO for every combination of --set values and every seed; one "
                    "row per run in --out, a summary per parameter value on stdout.")
    sweep.add_argument("scenario", help="path or shipped name ('default' for the built-in)")
    sweep.add_argument("--seeds", default=None, metavar="A:B",
                       help="seeds: START:STOP (STOP excluded), a list 1,2,3 or one seed "
                            "(default: the scenario's seed)")
    sweep.add_argument("--set", dest="assignments", action="append", default=[],
                       metavar="KEY.PATH=V1,V2",
                       help="sweep a scenario key over values, e.g. "
                            "robots[0].max_wheel_speed=0.5,1.0 (repeat for a grid)")
    sweep.add_argument("--backend", choices=BACKENDS, default="process",
                       help="where runs execute: serial (this process), process (local worker "
                            "processes), dask or ray (a cluster; extras) (default: process)")
    sweep.add_argument("--address", help="scheduler of a running cluster, e.g. "
                                         "tcp://HOST:8786 (dask) or HOST:6379 (ray)")
    sweep.add_argument("--workers", type=int, help="local workers (default: the CPU count)")
    sweep.add_argument("--duration", type=float, help="simulated seconds per run "
                                                      "(default: the scenario's world.duration)")
    sweep.add_argument("--chunk-size", type=int, help="runs per task (default: automatic)")
    sweep.add_argument("--resume", action="store_true",
                       help="skip the runs an earlier, interrupted sweep to --out finished")
    sweep.add_argument("--out", type=Path, required=True, help="results table (.csv or .parquet)")
    sweep.add_argument("--plot", type=Path, nargs="?", const=True, default=None,
                       metavar="IMAGE", help="plot the summary (default: next to --out, .png)")
    sweep.add_argument("--no-progress", action="store_true", help="no progress bar")
    sweep.set_defaults(func=cmd_sweep)
    return sweep


def parse_settings(texts: list[str], one_value: bool = False) -> dict[str, list[Any]]:
    """``--set KEY.PATH=V1,V2`` options -> {key path: values}; ScenarioError naming ``--set``
    for a malformed one, a key set twice, or (``one_value``, as ``run`` takes) several values."""
    from pymunk_bot.sweep import parse_assignment

    grid: dict[str, list[Any]] = {}
    for text in texts:
        try:
            key, values = parse_assignment(text)
        except ValueError as exc:
            raise ScenarioError("--set", "", str(exc)) from None
        if key in grid:
            raise ScenarioError("--set", "", f"'{key}' is set twice")
        if one_value and len(values) != 1:
            raise ScenarioError("--set", "", f"'{text[:80]}': one value per key (a list is "
                                             "[a, b]; `pymunk-bot sweep` runs several values)")
        grid[key] = values
    return grid


def scenario_with_settings(config: ScenarioConfig, spec: str | None,
                           settings: dict[str, list[Any]]) -> ScenarioConfig:
    """``config`` (loaded from ``spec``) with one value per key path set and validated again,
    as sweep validates its grid: a bad path or value is a ScenarioError naming it and the
    --set that caused it. A user's controller module is still looked for next to the file."""
    from pymunk_bot.config import parse_scenario, scenario_data
    from pymunk_bot.config.loader import resolve
    from pymunk_bot.sweep.grid import scenario_with

    path = resolve(spec)
    source = str(spec) if spec is not None else str(path)
    values = [(key, value) for key, (value,) in settings.items()]
    told = " ".join(f"{key}={value}" for key, value in values)
    try:
        data = scenario_with(scenario_data(config), values)
    except KeyError as exc:
        where, problem = exc.args
        raise ScenarioError(source, where, f"{problem} (--set {told})") from None
    try:
        return parse_scenario(data, source, base_dir=path.resolve().parent)
    except ScenarioError as exc:
        raise ScenarioError(source, exc.path, f"{exc.problem} (with --set {told})") from None


def cmd_sweep(args: argparse.Namespace) -> int:
    from pymunk_bot.sweep import BackendUnavailable, SweepInterrupted, format_table, parse_seeds, \
        plot_summary, run_sweep, summarize

    grid = parse_settings(args.assignments)
    try:
        seeds = parse_seeds(args.seeds) if args.seeds is not None else None
    except ValueError as exc:
        raise ScenarioError("--seeds", "", str(exc)) from None
    scenario = None if args.scenario == "default" else args.scenario
    plot = None
    if args.plot is not None:
        plot = args.out.with_suffix(".png") if args.plot is True else args.plot
    from pymunk_bot.controllers.python import batch_budget
    try:
        with batch_budget():
            rows = run_sweep(scenario, grid, seeds, backend=args.backend, address=args.address,
                             workers=args.workers, out=args.out, resume=args.resume,
                             duration=args.duration, chunk_size=args.chunk_size,
                             progress=not args.no_progress)
    except (ValueError, BackendUnavailable) as exc:  # each message names its option or path
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SweepInterrupted as exc:
        print(f"error: {exc}".replace("\n", " "), file=sys.stderr)
        return EXIT_INTERRUPTED
    groups = summarize(rows, list(grid))
    print(format_table(groups))
    passed = sum(bool(r["passed"]) for r in rows)
    print(f"{passed}/{len(rows)} runs passed; rows in {args.out}")
    if plot is not None:
        plot_summary(groups, plot, scenario=args.scenario)
        print(f"plot in {plot}")
    return EXIT_OK if passed == len(rows) else EXIT_SOME_FAILED

