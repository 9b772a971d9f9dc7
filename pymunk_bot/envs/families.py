"""A policy's results per world family in one table and one plot (``pymunk-bot evaluate
--generate office,maze,clutter --maps MAP.yaml``): where it generalizes and where it does not.

A row is a family's name and :func:`~pymunk_bot.envs.evaluation.summarize`'s summary of its
episodes. matplotlib is imported only by :func:`plot_families`.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

Row = tuple[str, dict[str, Any]]  # (family, summary)


def family_table(rows: list[Row]) -> str:
    """One line per family: episodes, contact-free success and its 95 % interval, arrivals,
    episodes with contact, mean time to goal of the arrivals [s]."""
    width = max([len("family")] + [len(name) for name, _ in rows])
    lines = [f"{'family':{width}s}  episodes  contact-free success (95 % CI)  goal reached  "
             f"with contact  time to goal"]
    for name, s in rows:
        success, reached, contact = s["success"], s["reached"], s["contact"]
        interval = f"{success['low']:.1%} - {success['high']:.1%}"
        lines.append(f"{name:{width}s}  {s['episodes']:8d}  {success['rate']:7.1%} "
                     f"({interval:>15s})       {reached['rate']:7.1%}       "
                     f"{contact['rate']:7.1%}  {s['time_to_goal']['mean']:9.1f} s")
    return "\n".join(lines)


def plot_families(rows: list[Row], path: str | Path, title: str = "") -> None:
    """A bar per family: contact-free success with its 95 % interval as error bars, and the
    goal-reached rate beside it. Written atomically; ValueError if matplotlib is missing."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ValueError("--plot needs matplotlib: pip install matplotlib") from None
    from pymunk_bot.outcomes.results import save_figure

    names = [name for name, _ in rows]
    success = [s["success"] for _, s in rows]
    rates = [100 * x["rate"] for x in success]
    errors = [[100 * max(0.0, x["rate"] - x["low"]) for x in success],  # rounding: >= 0
              [100 * max(0.0, x["high"] - x["rate"]) for x in success]]
    places = list(range(len(rows)))
    fig, ax = plt.subplots(figsize=(1.6 * len(rows) + 2.5, 3.8), constrained_layout=True)
    ax.bar([p - 0.2 for p in places], rates, 0.4, yerr=errors, capsize=4, color="tab:green",
           label="contact-free success (95 % CI)")
    ax.bar([p + 0.2 for p in places], [100 * s["reached"]["rate"] for _, s in rows], 0.4,
           color="tab:blue", alpha=0.5, label="goal reached")
    for p, rate in zip(places, rates):
        ax.text(p - 0.2, 2, f"{rate:.1f}", ha="center", fontsize=8, color="white")
    ax.set_xticks(places, names, rotation=15 if len(rows) > 4 else 0)
    ax.set_ylim(0, 105)
    ax.set_ylabel("episodes [%]")
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, fontsize=8, frameon=False)
    fig.suptitle(title or "per world family", fontsize=9)
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
