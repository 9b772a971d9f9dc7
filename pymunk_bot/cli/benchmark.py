"""`pymunk-bot benchmark`: controllers x suites x seeds, one row of metrics per episode, a
summary (mean and 95 % CI per controller) as Markdown and JSON, and a comparison plot."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.cli.arguments import EXIT_BAD_INPUT, EXIT_EXPECTATION_FAILED, EXIT_OK


def add_parser(subparsers) -> argparse.ArgumentParser:
    from pymunk_bot.sweep import BACKENDS

    bench = subparsers.add_parser(
        "benchmark", help="score navigation controllers on a suite of scenarios (metrics)",
        description="Run every --controller on every scenario of every SUITE for every seed; "
                    "one row of navigation metrics per episode in --out, the mean and 95 %% "
                    "confidence interval per controller on stdout (and in --summary). "
                    "See docs/benchmark.md.")
    bench.add_argument("suites", nargs="*", metavar="SUITE",
                       help="a scenario file, a folder of them, a generator spec, or a shipped "
                            "suite's name (see --list)")
    bench.add_argument("--list", action="store_true", help="list the shipped suites and exit")
    bench.add_argument("--controller", dest="controllers", action="append", default=[],
                       metavar="CONTROLLER",
                       help="a controller type (navigate, avoid, social_force, orca, ...) or a "
                            "YAML/JSON file with one 'controller:' block (repeatable)")
    bench.add_argument("--seeds", default="0:10", metavar="A:B",
                       help="seeds: START:STOP (STOP excluded), a list 1,2,3 or one seed "
                            "(default 0:10)")
    bench.add_argument("--backend", choices=BACKENDS, default="process",
                       help="where episodes run (default: process)")
    bench.add_argument("--address", help="scheduler of a running Dask or Ray cluster")
    bench.add_argument("--workers", type=int, help="local workers (default: the CPU count)")
    bench.add_argument("--duration", type=float,
                       help="simulated seconds per episode (default: each scenario's)")
    bench.add_argument("--out", type=Path, help="episode rows (.csv or .parquet)")
    bench.add_argument("--summary", type=Path, metavar="SUMMARY.json",
                       help="the summary as JSON, and as Markdown beside it (.md)")
    bench.add_argument("--plot", type=Path, metavar="IMAGE", help="the comparison plot")
    bench.add_argument("--personal-space", type=float, default=None, metavar="M",
                       help="clearance [m] that counts as a personal-space intrusion "
                            "(default 0.5)")
    bench.add_argument("--no-progress", action="store_true", help="no progress bar")
    bench.set_defaults(func=cmd_benchmark)
    return bench


def cmd_benchmark(args: argparse.Namespace) -> int:
    from pymunk_bot.benchmark import controller_choices, load_suite, markdown, run_benchmark, \
        shipped_suites, summarize, to_json
    from pymunk_bot.outcomes.navigation import Thresholds
    from pymunk_bot.outcomes.results import writable_problem, write_atomic
    from pymunk_bot.sweep import BackendUnavailable, parse_seeds

    if args.list:
        return _list(shipped_suites())
    if not args.suites:
        raise ScenarioError("benchmark", "SUITE", "name at least one suite (see --list)")
    if args.out is None:
        raise ScenarioError("benchmark", "--out", "required: where the episode rows go")
    try:
        seeds = parse_seeds(args.seeds)
        thresholds = Thresholds() if args.personal_space is None else Thresholds(
            personal_space=args.personal_space)
    except ValueError as exc:
        raise ScenarioError("--seeds" if "seed" in str(exc) else "--personal-space", "",
                            str(exc)) from None
    for path in (args.summary, args.plot):
        problem = None if path is None else writable_problem(path)
        if problem:
            raise ScenarioError(str(path), "", problem)
    choices = controller_choices(args.controllers)
    entries = [e for suite in args.suites for e in load_suite(suite)]
    try:
        rows = run_benchmark(entries, choices, seeds, thresholds, backend=args.backend,
                             workers=args.workers, address=args.address,
                             duration=args.duration, out=args.out,
                             progress=not args.no_progress)
    except (ValueError, BackendUnavailable) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    summary = summarize(rows)
    table = markdown(summary)
    print(table, end="")
    if args.summary is not None:
        write_atomic(args.summary, to_json(summary).encode("utf-8"))
        write_atomic(args.summary.with_suffix(".md"), table.encode("utf-8"))
    if args.plot is not None:
        from pymunk_bot.benchmark.plot import plot_summary
        plot_summary(summary, args.plot)
    failed = [r for r in rows if r["status"] != "ok"]
    for row in failed[:10]:
        print(f"failed: {row['scenario']} / {row['controller']} / seed {row['seed']}: "
              f"{row['error']}", file=sys.stderr)
    print(f"{len(rows)} episodes ({len(failed)} failed); rows in {args.out}")
    return EXIT_EXPECTATION_FAILED if failed else EXIT_OK


def _list(suites: dict[str, Path]) -> int:
    from pymunk_bot.benchmark import load_suite

    for name, path in suites.items():
        try:
            entries = load_suite(str(path))
            what = f"{len(entries)} scenarios"
        except ScenarioError as exc:
            what = f"(invalid: {exc})"
        print(f"{name:<16} {what}  ({path})")
    return EXIT_OK
