"""Running a benchmark: every suite scenario x controller x seed, one row per episode, on the
sweep's backends (serial, local processes, Dask, Ray).

An episode runs until the robot reaches its goal or the scenario's duration ends, or (a suite
with ``end_at_collision``, CrowdNav's protocol) until its first collision. A row holds
``suite``, ``scenario``, ``controller``, ``seed``, ``signature`` (of the metric thresholds),
``status`` ("ok", or "failed" with the ``error`` when the episode raised: a controller that
throws, say) and every metric of ``navmetrics.METRIC_NAMES``. Rows are plain data and depend on
nothing but their inputs: the same episodes give the same rows on every backend.
"""
from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path
from typing import Any, Iterable

from pymunk_bot.config import parse_scenario
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.navigation import METRIC_NAMES, Thresholds
from pymunk_bot.benchmark.controllers import ControllerChoice
from pymunk_bot.benchmark.suite import Entry, end_at_collision, episode_data

ROW_KEYS = ("run", "suite", "scenario", "controller", "seed", "signature", "status", "error",
            "sim_time") + METRIC_NAMES
MAX_EPISODES = 1_000_000
MAX_CHUNK = 16  # episodes per task at most (keeps the progress bar moving)
TASKS_PER_WORKER = 4


def _scenario(entry: Entry, choice: ControllerChoice, seed: int, duration: float | None
              ) -> Any:
    """The validated config of one episode: the suite's scenario with the first robot's
    controller replaced by ``choice``'s block."""
    data = episode_data(entry, seed, duration)
    robots = [dict(r) for r in data["robots"]]
    robots[0]["controller"] = dict(choice.block)
    data = dict(data, robots=robots)
    base_dir = choice.base_dir or entry.base_dir
    try:
        return parse_scenario(data, entry.source, base_dir=base_dir)
    except ScenarioError as exc:
        problem = exc.problem + (f" (controller '{choice.name}')" if "controller" in
                                 (exc.path or "") else "")
        raise ScenarioError(exc.source, exc.path, problem, exc.line) from None


def run_episode(entry: Entry, choice: ControllerChoice, seed: int, thresholds: Thresholds,
                duration: float | None = None) -> dict[str, Any]:
    """One episode's row; anything that goes wrong (a controller that raises, a layout
    without room for this seed) marks it failed, with the reason. Bad input is caught before
    the run by :func:`check_episodes`."""
    from pymunk_bot.outcomes.navigation import track
    from pymunk_bot.engine.simulation import Simulation

    row: dict[str, Any] = {"suite": entry.suite, "scenario": entry.scenario,
                           "controller": choice.name, "seed": seed,
                           "signature": thresholds.signature(), "status": "ok", "error": "",
                           "sim_time": 0.0}
    try:
        # The first seed's scenario was checked before the run (check_episodes); another
        # seed's draw may still find no room for its layout: that row fails, the rest go on.
        config = _scenario(entry, choice, seed, duration)
        sim = Simulation(config, seed=seed, source=entry.source)
        name = config.robots[0].name
        metrics = track(sim, name, thresholds)
        robot = sim.robots[name]
        stop_at_collision = end_at_collision(entry)
        for _ in range(round(config.world.duration / config.world.dt)):
            sim.step()
            if robot.goal_reached or (stop_at_collision and metrics.collided()):
                break
        row["sim_time"] = sim.time
        row.update(metrics.values())
    except Exception as exc:  # the controller (or the run) raised: keep the reason
        row.update(dict.fromkeys(METRIC_NAMES, math.nan))
        row["status"] = "failed"
        row["error"] = f"{type(exc).__name__}: {exc}".replace("\n", " ")[:500]
    return row


def run_chunk(base: dict, source: str, chunk: list[tuple[int, int, int, int]],
              duration: float | None, base_dir: str | None = None) -> list[dict[str, Any]]:
    """A backend task: episodes (row index, entry index, controller index, seed) of
    ``base``."""
    entries = [Entry(**e) for e in base["entries"]]
    choices = [ControllerChoice(**c) for c in base["controllers"]]
    thresholds = Thresholds(**base["thresholds"])
    return [{"run": i, **run_episode(entries[e], choices[c], seed, thresholds, duration)}
            for i, e, c, seed in chunk]


def episodes(entries: list[Entry], choices: list[ControllerChoice], seeds: list[int]
             ) -> list[tuple[int, int, int, int]]:
    """Every (row index, entry, controller, seed), in row order; ValueError naming the
    product when there would be more than MAX_EPISODES (counted before any is listed)."""
    count = len(entries) * len(choices) * len(seeds)
    if count > MAX_EPISODES:
        raise ValueError(f"--seeds: {len(entries)} scenarios x {len(choices)} controllers x "
                         f"{len(seeds)} seeds = {count} episodes; at most {MAX_EPISODES} per "
                         "benchmark")
    every = [(e, c, s) for e in range(len(entries)) for c in range(len(choices)) for s in seeds]
    return [(i, e, c, s) for i, (e, c, s) in enumerate(every)]


def check_episodes(entries: list[Entry], choices: list[ControllerChoice], seed: int,
                   duration: float | None) -> None:
    """Build every scenario with every controller once (the first seed), so bad input is
    one ScenarioError before anything runs."""
    for entry in entries:
        for choice in choices:
            _scenario(entry, choice, seed, duration)


def run_benchmark(entries: list[Entry], choices: list[ControllerChoice], seeds: Iterable[int],
                  thresholds: Thresholds | None = None, backend: str = "serial",
                  workers: int | None = None, address: str | None = None,
                  duration: float | None = None, out: str | Path | None = None,
                  progress: bool = False) -> list[dict[str, Any]]:
    """Every episode's row, in order (``run``: suite scenario, controller, seed); with ``out`` (.csv
    or .parquet) the table is also written atomically. Bad input raises ScenarioError or
    ValueError before anything runs."""
    from pymunk_bot.sweep.backends import check_workers, default_workers, run_chunks
    from pymunk_bot.sweep.output import check_output, write_table
    from pymunk_bot.sweep.progress import Progress

    thresholds = thresholds or Thresholds()
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("--seeds: no seeds")
    check_workers(workers)
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"--duration must be > 0 (got {duration})")
    if out is not None:
        check_output(Path(out))
    todo = episodes(entries, choices, seeds)
    check_episodes(entries, choices, seeds[0], duration)
    n_workers = 1 if backend == "serial" else (workers or default_workers())
    size = min(MAX_CHUNK, max(1, math.ceil(len(todo) / (n_workers * TASKS_PER_WORKER))))
    chunks = [todo[i:i + size] for i in range(0, len(todo), size)]
    base = {"entries": [asdict(e) for e in entries],
            "controllers": [asdict(c) for c in choices], "thresholds": asdict(thresholds)}
    rows: list[dict[str, Any]] = []
    with Progress(len(todo), "benchmark", "episodes", enabled=progress) as shown:
        for done in run_chunks(backend, base, "benchmark", chunks, duration, workers, address,
                               None, task=run_chunk):
            rows.extend(done)
            shown.update(len(done))
    rows.sort(key=lambda r: r["run"])
    if out is not None:
        write_table(Path(out), rows)
    return rows
