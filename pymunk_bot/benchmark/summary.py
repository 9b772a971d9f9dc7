"""A benchmark's summary: per controller, every metric's mean and 95 % confidence interval.

The interval is Student's t: mean +- t(0.975, n - 1) * s / sqrt(n), over the episodes where
the metric is finite (``time_to_goal`` is NaN without success; ``min_distance_to_human`` and
``min_time_to_collision`` are inf without humans on course): ``n`` says how many. Failed
episodes (the run raised) are counted apart and left out. Rows measured with different metric
thresholds (signatures) are never mixed: :func:`summarize` refuses them.
"""
from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from pymunk_bot.outcomes.navigation import BY_NAME, METRIC_NAMES

# Columns of the Markdown table (all metrics are in the JSON).
TABLE = ("success", "reached", "collision", "collision_human", "timeout", "spl",
         "time_to_goal", "path_length", "min_distance_to_human", "personal_space_time",
         "discomfort", "human_impulse", "peak_human_force")
# Said under every table: the columns whose meanings overlap, and how.
OVERLAPS = ("success implies reached (reached also counts arrivals after a collision); "
            "collision_human is part of collision; where episodes go on after a collision "
            "(suites without end_at_collision) an episode may count collision and reached, or "
            "collision and timeout; spl weighs reached, not success")


class MixedSignatures(ValueError):
    """Rows measured with different thresholds."""


def interval(values: list[float]) -> dict[str, float]:
    """Mean, 95 % half-width and count of the finite ``values``."""
    from scipy.stats import t

    x = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    n = int(x.size)
    if n == 0:
        return {"mean": math.nan, "ci95": math.nan, "n": 0}
    half = float(t.ppf(0.975, n - 1) * x.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan
    return {"mean": float(x.mean()), "ci95": half, "n": n}


def summarize(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """{"signature", "controllers": {name: {"episodes", "failed", "metrics": {metric:
    {"mean", "ci95", "n"}}}}} in the rows' controller order."""
    signatures = sorted({str(r["signature"]) for r in rows})
    if len(signatures) > 1:
        raise MixedSignatures(f"the rows were measured with different metric thresholds "
                              f"(signatures {', '.join(signatures)}): summarize each apart")
    out: dict[str, Any] = {"signature": signatures[0] if signatures else None,
                           "controllers": {}}
    names = list(dict.fromkeys(str(r["controller"]) for r in rows))
    for name in names:
        mine = [r for r in rows if str(r["controller"]) == name]
        ok = [r for r in mine if r.get("status") == "ok"]
        out["controllers"][name] = {
            "episodes": len(mine), "failed": len(mine) - len(ok),
            "metrics": {m: interval([_number(r.get(m)) for r in ok]) for m in METRIC_NAMES}}
    return out


def _number(value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _cell(stat: dict[str, float]) -> str:
    if stat["n"] == 0:
        return "n/a"
    if math.isnan(stat["ci95"]):
        return f"{stat['mean']:.3g}"
    return f"{stat['mean']:.3g} ± {stat['ci95']:.2g}"


def markdown(summary: dict[str, Any], columns: tuple[str, ...] = TABLE) -> str:
    """The summary as a Markdown table: one row per controller, mean ± 95 % CI."""
    head = ["controller", "episodes"] + [
        f"{c} [{BY_NAME[c].unit}]" if BY_NAME[c].unit else c for c in columns]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, block in summary["controllers"].items():
        failed = f" ({block['failed']} failed)" if block["failed"] else ""
        cells = [name, f"{block['episodes']}{failed}"] + [
            _cell(block["metrics"][c]) for c in columns]
        lines.append("| " + " | ".join(cells) + " |")
    lines.append(f"\nMetric thresholds signature: `{summary['signature']}`. Overlapping "
                 f"columns: {OVERLAPS}.")
    return "\n".join(lines) + "\n"


def to_json(summary: dict[str, Any]) -> str:
    """JSON text (NaN as null: strict JSON)."""
    def clean(value: Any) -> Any:
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value
    return json.dumps(clean(summary), indent=2) + "\n"
