"""Per parameter value: how many runs, how many passed, mean and spread of every metric."""
from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from typing import Any

# Shown in the printed table (every numeric field is in the Summary); per robot, by suffix.
HEADLINE = ("goal_reached", "time_to_goal", "collisions", "min_clearance")
# The headline metrics' units, as the plot's axes show them (goal_reached is plotted as a rate)
HEADLINE_UNITS = {"goal_reached": "% of runs", "time_to_goal": "time [s]",
                  "collisions": "contact episodes", "min_clearance": "distance [m]"}
NOT_METRICS = {"run", "seed", "steps", "sim_time"}


@dataclass(frozen=True)
class Stat:
    n: int  # runs with a value (time_to_goal is empty when the goal was not reached)
    mean: float
    std: float  # sample standard deviation (0 for one value)


@dataclass(frozen=True)
class Group:
    """The runs of one swept value (or all runs, ``key == "all"``): their count, pass rate and
    each metric's mean and spread."""

    key: str  # the swept key path, or "all"
    value: Any
    runs: int
    pass_rate: float  # [0, 1]
    metrics: dict[str, Stat]


def metric_columns(rows: list[dict], swept: list[str]) -> list[str]:
    """Numeric and boolean result columns (pose components and the like excluded)."""
    columns: dict[str, None] = {}
    for row in rows:
        for key, value in row.items():
            if key in NOT_METRICS or key in swept or "[" in key or key == "passed":
                continue
            if isinstance(value, (bool, int, float)) and value is not None:
                columns.setdefault(key, None)
    return list(columns)


def _stat(values: list[float | None]) -> Stat | None:
    known = [float(v) for v in values if v is not None and not
             (isinstance(v, float) and math.isnan(v))]  # a run without the metric is skipped
    if not known:
        return None
    std = statistics.stdev(known) if len(known) > 1 else 0.0
    return Stat(len(known), statistics.fmean(known), std)


def summarize(rows: list[dict], swept: list[str]) -> list[Group]:
    """One group per (swept key, value) in first-seen order; one "all" group without keys."""
    metrics = metric_columns(rows, swept)
    keys = swept or ["all"]
    groups = []
    for key in keys:
        values: dict[str, Any] = {}
        for row in rows:
            value = row.get(key, "all")
            values.setdefault(repr(value), value)
        for label, value in values.items():
            members = [r for r in rows if repr(r.get(key, "all")) == label]
            stats = {m: s for m in metrics
                     if (s := _stat([r.get(m) for r in members])) is not None}
            passed = sum(bool(r.get("passed")) for r in members)
            groups.append(Group(key, value, len(members), passed / len(members), stats))
    return groups


def format_table(groups: list[Group]) -> str:
    """The printed summary: pass rate and the headline metrics, mean +- std."""
    if not groups:
        return "(no runs)"
    shown = [m for m in groups[0].metrics if m.rsplit(".", 1)[-1] in HEADLINE]
    header = ["parameter", "value", "runs", "pass"] + shown
    lines = [header]
    for g in groups:
        cells = [g.key, str(g.value), str(g.runs), f"{100 * g.pass_rate:.0f}%"]
        for m in shown:
            s = g.metrics.get(m)
            if s is None:
                cells.append("-")
            elif m.endswith("goal_reached"):
                cells.append(f"{100 * s.mean:.0f}%")
            else:
                cells.append(f"{s.mean:.3g} ± {s.std:.2g}" + (f" (n={s.n})" if s.n < g.runs
                                                              else ""))
        lines.append(cells)
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip()
                     for line in lines)
