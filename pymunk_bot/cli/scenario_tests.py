"""Scenarios as regression tests: find scenario files with an ``expect`` block, run them (in
parallel over the cores) and report which expectation failed and by how much.

Used by ``pymunk-bot test [PATHS...]`` and by the pytest plugin (:mod:`pymunk_bot.cli.pytest_plugin`).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import yaml

from pymunk_bot.config.errors import ScenarioError

YAML_SUFFIXES = (".yaml", ".yml")


@dataclass
class Outcome:
    """The result of running one scenario file as a test."""

    path: str
    name: str = ""
    status: str = "passed"  # passed, failed, error (bad input)
    failures: list[str] = field(default_factory=list)  # one line per failed expectation
    error: str = ""  # the one-line ScenarioError message
    sim_time: float = 0.0  # [s] simulated
    wall_time: float = 0.0  # [s] spent

    @property
    def passed(self) -> bool:
        return self.status == "passed"


def has_expect_block(path: Path) -> bool:
    """True when a YAML file is a mapping with a non-empty top-level ``expect`` key.

    Unreadable or unparsable files count as scenarios (so the run reports their error)
    only when their text mentions ``expect:`` at the start of a line.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return False
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError:
        return any(line.startswith("expect:") for line in text.splitlines())
    return isinstance(data, dict) and bool(data.get("expect"))


def discover(paths: Sequence[str | Path]) -> list[Path]:
    """Scenario files with expectations under ``paths`` (files or directories, recursively).

    A file named explicitly is always included if it has an ``expect`` block; so is every
    such ``*.yaml`` / ``*.yml`` below a directory. Sorted, without duplicates.
    """
    found: dict[Path, None] = {}
    for spec in paths:
        path = Path(spec)
        if path.is_dir():
            candidates = sorted(p for p in path.rglob("*") if p.suffix in YAML_SUFFIXES
                                and p.is_file())
        elif path.is_file():
            candidates = [path]
        else:
            raise ScenarioError(str(spec), "", "no such file or directory")
        for candidate in candidates:
            if has_expect_block(candidate):
                found.setdefault(candidate, None)
    return list(found)


def run_scenario(path: str | Path, seed: int | None = None,
                 duration: float | None = None) -> Outcome:
    """Load, run for the scenario's duration and check the expectations of one file."""
    # Here, not at the top: the pytest plugin imports this module in every pytest process.
    from pymunk_bot.config import load_scenario
    from pymunk_bot.engine.simulation import Simulation
    from pymunk_bot.outcomes.expectations import unexpected_failures

    outcome = Outcome(str(path))
    started = time.perf_counter()
    try:
        config = load_scenario(path)
        outcome.name = config.name
        sim = Simulation(config, seed=seed, source=str(path))
        sim.run(config.world.duration if duration is None else duration)
    except ScenarioError as exc:
        outcome.status, outcome.error = "error", str(exc)
        outcome.wall_time = time.perf_counter() - started
        return outcome
    checks = sim.check_expectations()
    outcome.failures = [c.miss() for c in checks if not c.passed]
    statuses = {r.name: (r.controller.status, r.controller.message)
                for r in sim.robots.values() if r.controller is not None}
    outcome.failures += [f"{name}: controller failed: {message}"
                         for name, message in unexpected_failures(config.expect, statuses)]
    outcome.status = "passed" if not outcome.failures else "failed"
    outcome.sim_time = sim.time
    outcome.wall_time = time.perf_counter() - started
    return outcome


def _run_one(args: tuple) -> Outcome:
    return run_scenario(*args)


def run_all(paths: list[Path], seed: int | None = None, jobs: int | None = None) -> list[Outcome]:
    """Run every file, in parallel over ``jobs`` processes (default: the CPU count)."""
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(paths)))
    work = [(str(p), seed) for p in paths]
    if jobs == 1:
        return [_run_one(w) for w in work]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(_run_one, work))


def format_table(outcomes: list[Outcome]) -> str:
    """scenario | result | simulated / wall seconds | what failed, one row per scenario."""
    rows = [("scenario", "result", "sim s", "wall s", "details")]
    for o in outcomes:
        details = o.error if o.status == "error" else "; ".join(o.failures)
        rows.append((o.name or Path(o.path).stem, o.status.upper() if not o.passed else "ok",
                     f"{o.sim_time:.1f}", f"{o.wall_time:.2f}", details))
    widths = [max(len(r[i]) for r in rows) for i in range(4)]
    lines = []
    for r in rows:
        lines.append("  ".join(r[i].ljust(widths[i]) for i in range(4)) + "  " + r[4])
    lines.insert(1, "  ".join("-" * w for w in widths) + "  " + "-" * 7)
    return "\n".join(line.rstrip() for line in lines)
