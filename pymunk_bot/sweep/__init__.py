"""Parameter sweeps: a grid of scenario values times seeds, run on one of several backends.

    from pymunk_bot.sweep import run_sweep
    rows = run_sweep("corridor", grid={"robots[0].max_wheel_speed": [0.5, 1.0]},
                     seeds=range(20), backend="process", out="results.csv")

See docs/sweeps.md. The same sweep gives the same rows (order aside) on every backend.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Iterable, Mapping

from pymunk_bot.config import ScenarioConfig, load_scenario, parse_scenario, resolve, scenario_data
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.sweep.backends import BACKENDS, BackendUnavailable, default_workers, run_chunks
from pymunk_bot.sweep.grid import Run, build_grid, parse_assignment, parse_seeds
from pymunk_bot.sweep.output import Journal, check_output, journal_path, read_journal, read_table, write_table
from pymunk_bot.sweep.summary import Group, format_table, summarize
from pymunk_bot.sweep.summary_plot import plot_summary

class SweepInterrupted(RuntimeError):
    """A run or a worker failed mid-sweep; the finished rows are kept for ``resume``."""


MAX_CHUNK = 32  # runs per task at most: keeps the progress bar and the journal moving
TASKS_PER_WORKER = 4  # enough tasks that a slow chunk does not leave workers idle


def chunk_runs(runs: list[Run], workers: int, chunk_size: int | None = None) -> list[list[Run]]:
    """Split the runs into tasks of ``chunk_size`` (default: about 4 tasks per worker, at most
    MAX_CHUNK runs each), so each backend's per-task overhead is paid per chunk, not per run."""
    if chunk_size is None:
        chunk_size = min(MAX_CHUNK, max(1, math.ceil(len(runs) / (workers * TASKS_PER_WORKER))))
    if chunk_size < 1:
        raise ValueError(f"--chunk-size must be >= 1 (got {chunk_size})")
    return [runs[i:i + chunk_size] for i in range(0, len(runs), chunk_size)]


def _load(scenario: str | Path | dict | ScenarioConfig | None, base_dir: str | Path | None
          ) -> tuple[ScenarioConfig, str, str | None]:
    """The config, its name in messages, and the folder its Python controllers come from."""
    if isinstance(scenario, ScenarioConfig):
        return scenario, f"scenario '{scenario.name}'", None if base_dir is None else str(base_dir)
    if isinstance(scenario, dict):
        folder = None if base_dir is None else str(Path(base_dir).resolve())
        return parse_scenario(scenario, "<dict>", base_dir=folder), "<dict>", folder
    folder = str(Path(base_dir).resolve() if base_dir is not None
                 else resolve(scenario).resolve().parent)  # beside the file, as `run` does
    return load_scenario(scenario), "default" if scenario is None else str(scenario), folder


def _resumed_rows(out: Path, runs: list[Run], source: str) -> dict[int, dict]:
    """Finished rows of an earlier attempt at this sweep, checked against the grid."""
    by_index = {run.index: run for run in runs}
    done: dict[int, dict] = {}
    for row in read_table(out) + read_journal(journal_path(out)):
        run = by_index.get(row["run"]) if "run" in row else None
        expected = {} if run is None else {"seed": run.seed, **dict(run.values)}
        if run is None or any(row.get(k) != v and row.get(k) != repr(v)
                              for k, v in expected.items()):
            raise ScenarioError(str(out), "", "holds rows of a different sweep (other --set, "
                                              "--seeds or scenario); choose another --out")
        done[run.index] = row
    return done


def run_sweep(scenario: str | Path | dict | ScenarioConfig | None,
              grid: Mapping[str, Iterable[Any]] | None = None,
              seeds: Iterable[int] | str | None = None, backend: str = "serial",
              address: str | None = None, workers: int | None = None,
              out: str | Path | None = None, resume: bool = False,
              duration: float | None = None, chunk_size: int | None = None,
              progress: bool = False, base_dir: str | Path | None = None) -> list[dict]:
    """Run every combination of ``grid`` values (key path -> values) for every seed.

    A ``python`` controller's module is looked for beside the scenario file first (as
    ``pymunk-bot run`` does), or in ``base_dir`` when given (for a dict or a config).

    Returns one row per run, sorted by run index (see docs/sweeps.md for the columns). With
    ``out`` (.csv or .parquet), rows are journalled as they arrive and the table is written
    atomically at the end; ``resume`` skips the runs an earlier attempt finished.
    Bad keys or values raise ScenarioError before anything runs.
    """
    config, source, folder = _load(scenario, base_dir)
    values = {str(k): list(v) for k, v in (grid or {}).items()}  # key path -> its values
    if isinstance(seeds, str):
        seeds = parse_seeds(seeds)
    seeds = [config.seed] if seeds is None else [int(s) for s in seeds]
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend '{backend}' (choose from {', '.join(BACKENDS)})")
    if address is not None and backend not in ("dask", "ray"):
        raise ValueError(f"--address is for the dask and ray backends, not '{backend}'")
    if workers is not None and not 1 <= workers <= 1024:
        raise ValueError(f"--workers must be in [1, 1024] (got {workers})")
    if chunk_size is not None and chunk_size < 1:
        raise ValueError(f"--chunk-size must be >= 1 (got {chunk_size})")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"--duration must be > 0 (got {duration})")
    runs = build_grid(config, source, values, seeds, folder)  # every combination validated
    out = None if out is None else Path(out)
    done: dict[int, dict] = {}
    if out is not None:
        check_output(out)
        if resume:
            done = _resumed_rows(out, runs, source)
        elif journal_path(out).exists():
            raise ScenarioError(str(out), "", f"an unfinished sweep left rows in "
                                              f"{journal_path(out).name}; pass --resume to "
                                              "finish it, or delete that file")
    todo = [run for run in runs if run.index not in done]
    n_workers = 1 if backend == "serial" else (workers or default_workers())
    chunks = chunk_runs(todo, n_workers, chunk_size)
    base = scenario_data(config)
    journal = Journal(journal_path(out)) if out is not None and todo else None
    from tqdm import tqdm

    bar = tqdm(total=len(runs), initial=len(done), unit="run", desc="sweep",
               disable=None if progress else True, leave=False)
    try:
        for rows in run_chunks(backend, base, source, chunks, duration, workers, address,
                               folder):
            if journal is not None:
                journal.write(rows)
            for row in rows:
                done[row["run"]] = row
            bar.update(len(rows))
    except (ScenarioError, BackendUnavailable, KeyboardInterrupt):
        raise
    except Exception as exc:  # a worker died, a run raised: say where the finished rows are
        kept = f"; {len(done)} finished rows are in {journal.path}, rerun with --resume to " \
               "finish" if journal is not None else ""
        raise SweepInterrupted(f"the sweep stopped: {type(exc).__name__}: {exc}{kept}") from exc
    finally:
        bar.close()
        if journal is not None:
            journal.close()
    rows = [done[i] for i in sorted(done)]
    if out is not None:
        write_table(out, rows)
        journal_path(out).unlink(missing_ok=True)
    return rows


__all__ = ["BACKENDS", "BackendUnavailable", "SweepInterrupted", "Group", "Run", "format_table", "parse_assignment",
           "parse_seeds", "plot_summary", "run_sweep", "summarize"]
