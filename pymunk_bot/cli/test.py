"""`pymunk-bot test`: scenarios with an `expect` block as regression tests."""
from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from typing import TYPE_CHECKING

from pymunk_bot.config.errors import ControllerError
from pymunk_bot.cli.arguments import jobs_count, seed_number

if TYPE_CHECKING:  # the runner (and the simulation) loads when `test` runs, not with the parser
    from pymunk_bot.cli.scenario_tests import Outcome


def command(args: argparse.Namespace) -> int:
    """``pymunk-bot test``: exit 0 all held, 1 an expectation failed, 2 a file is bad input."""
    specs = args.paths or _default_specs()
    if not specs:
        print("error: test: no ./scenarios folder here; name scenario files or folders "
              "(pymunk-bot test PATH...)", file=sys.stderr)
        return 2
    from pymunk_bot.cli.scenario_tests import discover, format_table

    paths = discover(specs)
    if not paths:
        print(f"no scenario files with an 'expect' block under {', '.join(map(str, specs))}")
        return 0
    started = time.perf_counter()
    from pymunk_bot.controllers.python import batch_budget

    with batch_budget():
        outcomes = _run_with_progress(paths, args.seed, args.jobs)
    print(format_table(outcomes))
    counts = {s: sum(o.status == s for o in outcomes) for s in ("passed", "failed", "error")}
    print(f"{counts['passed']} passed, {counts['failed']} failed, {counts['error']} invalid "
          f"in {time.perf_counter() - started:.1f} s")
    sys.stdout.flush()
    if counts["error"]:
        return 2
    return 1 if counts["failed"] else 0


def _run_with_progress(paths: list[Path], seed: int | None, jobs: int | None) -> list[Outcome]:
    """Every file's outcome (in the order given), in parallel over ``jobs`` processes (default:
    the CPU count), one line on stderr as each finishes; a controller bug fails its scenario."""
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(paths)))
    outcomes: dict[int, Outcome] = {}

    def done(k: int, outcome: Outcome) -> None:
        outcomes[k] = outcome
        label = "ok" if outcome.passed else outcome.status.upper()
        print(f"[{len(outcomes)}/{len(paths)}] {outcome.name or paths[k].stem}: {label} "
              f"({outcome.wall_time:.1f} s)", file=sys.stderr, flush=True)

    if jobs == 1:
        for k, path in enumerate(paths):
            done(k, _run_guarded(str(path), seed))
    else:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            futures = {pool.submit(_run_guarded, str(path), seed): k for k, path in enumerate(paths)}
            for future in as_completed(futures):
                done(futures[future], future.result())
    return [outcomes[k] for k in range(len(paths))]


def _run_guarded(path: str, seed: int | None) -> Outcome:
    """:func:`run_scenario`, with a controller's bug (or overrun) as the scenario's failure."""
    started = time.perf_counter()
    try:
        from pymunk_bot.cli.scenario_tests import run_scenario

        return run_scenario(path, seed=seed)
    except ControllerError as exc:
        from pymunk_bot.cli.scenario_tests import Outcome

        return Outcome(path, status="failed", failures=[f"controller {exc}"],
                       wall_time=time.perf_counter() - started)


def _default_specs() -> list[str]:
    """./scenarios if there is one, else the shipped scenarios of this installation."""
    if Path("scenarios").is_dir():
        return ["scenarios"]
    from pymunk_bot.config.loader import shipped_scenario_dirs

    dirs = [str(d) for d in shipped_scenario_dirs()]
    if dirs:
        print(f"no ./scenarios here: running the shipped scenarios in {', '.join(dirs)}")
    return dirs


def add_parser(sub) -> None:
    """Register the ``test`` subcommand on the CLI's subparsers."""
    test = sub.add_parser("test", help="run scenarios with an 'expect' block as regression tests")
    test.add_argument("paths", nargs="*", help="files or directories (default: ./scenarios)")
    test.add_argument("--jobs", "-j", type=jobs_count, help="parallel processes (default: CPU count)")
    test.add_argument("--seed", type=seed_number, help="override every scenario's seed")
    test.set_defaults(func=command)
