"""The sweep summary as a figure (matplotlib, imported here only: the rest of the sweep needs
none)."""
from __future__ import annotations

import math
from pathlib import Path

from pymunk_bot.sweep.summary import HEADLINE, HEADLINE_UNITS, Group

# Units of the scenario keys a sweep most often varies, by the key's last name (the scenario
# format's units); a key not listed is labelled by its path alone.
KEY_UNITS = {"max_wheel_speed": "m/s", "max_speed": "m/s", "max_accel": "m/s²",
             "max_angular_speed": "rad/s", "max_steer": "rad", "max_steer_rate": "rad/s",
             "radius": "m", "mass": "kg", "track_width": "m", "wheelbase": "m", "dt": "s",
             "duration": "s", "tolerance": "m", "max_range": "m", "min_range": "m",
             "fov": "rad", "rate": "Hz", "beams": "beams", "particles": "particles"}


def axis_label(name: str, units: dict[str, str]) -> str:
    """``name [unit]`` when the unit of the name's last part is known, else ``name``."""
    unit = units.get(name.rsplit(".", 1)[-1].split("[")[0])
    return f"{name} [{unit}]" if unit else name


def plot_summary(groups: list[Group], path: str | Path, scenario: str | None = None) -> None:
    """Pass rate and headline metrics (mean, error bar = std) against each swept value, titled
    with what was swept, on which ``scenario`` (a name or path), and how many runs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from pymunk_bot.outcomes.results import save_figure

    keys = list(dict.fromkeys(g.key for g in groups))
    shown = [m for m in groups[0].metrics if m.rsplit(".", 1)[-1] in HEADLINE] if groups else []
    panels = ["pass rate"] + shown
    fig, axes = plt.subplots(len(keys), len(panels), squeeze=False,
                             figsize=(3.2 * len(panels), 2.6 * len(keys)))
    for row, key in enumerate(keys):
        mine = [g for g in groups if g.key == key]
        labels = [str(g.value) for g in mine]
        x = range(len(mine))
        for col, panel in enumerate(panels):
            ax = axes[row][col]
            if panel == "pass rate":
                ax.bar(x, [100 * g.pass_rate for g in mine], color="tab:green")
                ax.set_ylim(0, 100)
                ax.set_ylabel("% of runs")
            elif panel.endswith("goal_reached"):  # a rate, like the pass rate
                ax.bar(x, [100 * g.metrics[panel].mean if panel in g.metrics else 0.0
                           for g in mine], color="tab:blue")
                ax.set_ylim(0, 100)
                ax.set_ylabel(HEADLINE_UNITS[panel.rsplit(".", 1)[-1]])
            else:
                means = [g.metrics[panel].mean if panel in g.metrics else math.nan for g in mine]
                stds = [g.metrics[panel].std if panel in g.metrics else 0.0 for g in mine]
                ax.errorbar(list(x), means, yerr=stds, fmt="o-", capsize=3)
                ax.set_ylabel(HEADLINE_UNITS[panel.rsplit(".", 1)[-1]])
            ax.set_title(panel, fontsize="medium")
            ax.set_xticks(list(x), labels)
            ax.set_xlabel(axis_label(key, KEY_UNITS))
    runs = sum(g.runs for g in groups if g.key == keys[0]) if keys else 0
    where = f" on {scenario}" if scenario else ""
    fig.suptitle(f"Sweep of {', '.join(keys)}{where}: {runs} runs", fontweight="bold")
    fig.text(0.5, 0.005, "points: mean over the runs of each value; error bars: ± 1 standard "
             "deviation", ha="center", va="bottom", fontsize="small", color="0.35")
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)
