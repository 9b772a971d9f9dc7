"""What a worker does: run a chunk of the grid and turn each result into one flat row.

Everything here is a plain top-level function of plain data, so any backend (a process pool,
Dask, Ray) can ship it to a worker.
"""
from __future__ import annotations

from typing import Any

from pymunk_bot.config import parse_scenario
from pymunk_bot.sweep.grid import Run, scenario_with

# Result keys left out of rows: they measure the machine, not the run, and would make the
# same sweep differ between backends.
MACHINE_DEPENDENT = ("wall_time", "real_time_factor")


def flatten(prefix: str, value: Any, out: dict[str, Any]) -> None:
    """Nested dicts and lists -> ``prefix.key`` and ``prefix[i]`` columns of plain values."""
    if isinstance(value, dict):
        for key, item in value.items():
            flatten(f"{prefix}.{key}" if prefix else str(key), item, out)
    elif isinstance(value, (list, tuple)):
        for i, item in enumerate(value):
            flatten(f"{prefix}[{i}]", item, out)
    else:
        # numpy scalars -> Python: rows must be JSON- and pickle-plain on every backend;
        # "" -> None: an empty CSV cell reads back as None, so both mean "no value"
        out[prefix] = value.item() if hasattr(value, "item") else (None if value == "" else value)


def result_row(run: Run, result: dict) -> dict[str, Any]:
    """One row: run index, swept values, seed, passed, sim_time, then every robot's fields."""
    row: dict[str, Any] = {"run": run.index}
    for path, value in run.values:
        row[path] = value if not isinstance(value, (list, dict)) else repr(value)
    row["seed"] = run.seed
    row["passed"] = bool(result["passed"])
    row["sim_time"] = result["sim_time"]
    row["steps"] = result["steps"]
    for name, fields in result["robots"].items():
        flatten(name, fields, row)
    for key in MACHINE_DEPENDENT:
        row.pop(key, None)
    return row


def run_one(base: dict, source: str, run: Run, duration: float | None,
            base_dir: str | None = None) -> dict[str, Any]:
    """Build the run's scenario (Python controllers looked for in ``base_dir`` first, as for
    the scenario file), simulate it headless and return its row."""
    config = parse_scenario(scenario_with(base, run.values), source, base_dir=base_dir)
    from pymunk_bot.engine.simulation import Simulation  # here: the CLI's parser imports sweep

    sim = Simulation(config, seed=run.seed, source=source)
    sim.run(config.world.duration if duration is None else duration)
    return result_row(run, sim.result())


def run_chunk(base: dict, source: str, runs: list[Run], duration: float | None,
              base_dir: str | None = None) -> list[dict[str, Any]]:
    """Several runs in one task, so the per-task overhead of a backend is paid once."""
    return [run_one(base, source, run, duration, base_dir) for run in runs]
