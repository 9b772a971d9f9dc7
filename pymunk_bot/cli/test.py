"""`pymunk-bot test`: scenarios with an `expect` block as regression tests."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..scenario_tests import discover, format_table, run_all
from .arguments import jobs_count, seed_number


def command(args: argparse.Namespace) -> int:
    """``pymunk-bot test``: exit 0 all held, 1 an expectation failed, 2 a file is bad input."""
    specs = args.paths or _default_specs()
    if not specs:
        print("error: test: no ./scenarios folder here; name scenario files or folders "
              "(pymunk-bot test PATH...)", file=sys.stderr)
        return 2
    paths = discover(specs)
    if not paths:
        print(f"no scenario files with an 'expect' block under {', '.join(map(str, specs))}")
        return 0
    started = time.perf_counter()
    outcomes = run_all(paths, seed=args.seed, jobs=args.jobs)
    print(format_table(outcomes))
    counts = {s: sum(o.status == s for o in outcomes) for s in ("passed", "failed", "error")}
    print(f"{counts['passed']} passed, {counts['failed']} failed, {counts['error']} invalid "
          f"in {time.perf_counter() - started:.1f} s")
    sys.stdout.flush()
    if counts["error"]:
        return 2
    return 1 if counts["failed"] else 0


def _default_specs() -> list[str]:
    """./scenarios if there is one, else the shipped scenarios of this installation."""
    if Path("scenarios").is_dir():
        return ["scenarios"]
    from ..config.loader import shipped_scenario_dirs

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
