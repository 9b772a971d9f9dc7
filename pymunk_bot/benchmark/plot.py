"""The comparison plot of a benchmark summary (matplotlib, imported only here)."""
from __future__ import annotations

from pathlib import Path
from typing import Any

from pymunk_bot.outcomes.navigation import BY_NAME

PLOTTED = ("success", "collision_human", "spl", "time_to_goal", "min_distance_to_human",
           "personal_space_time", "human_impulse", "max_jerk")


def plot_summary(summary: dict[str, Any], path: str | Path, title: str = "") -> None:
    """One bar chart per metric of PLOTTED: a bar per controller, the 95 % CI as error bars.
    Written atomically (an image file beside ``path``, renamed over it)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ValueError("--plot needs matplotlib: pip install matplotlib") from None
    from pymunk_bot.outcomes.results import save_figure

    names = list(summary["controllers"])
    fig, axes = plt.subplots(2, 4, figsize=(16, 7), constrained_layout=True)
    for ax, metric in zip(axes.ravel(), PLOTTED):
        stats = [summary["controllers"][n]["metrics"][metric] for n in names]
        means = [s["mean"] for s in stats]
        errors = [0.0 if s["ci95"] != s["ci95"] else s["ci95"] for s in stats]
        ax.bar(range(len(names)), means, yerr=errors, capsize=4, color="tab:blue", alpha=0.8)
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right")
        unit = BY_NAME[metric].unit
        ax.set_title(f"{metric} [{unit}]" if unit else metric)
    fig.suptitle(title or f"benchmark (thresholds {summary['signature']}), mean and 95 % CI")
    try:
        save_figure(fig, path, dpi=100)
    finally:
        plt.close(fig)
