"""The sweep summary as a figure (matplotlib, imported here only: the rest of the sweep needs
none)."""
from __future__ import annotations

import math
from pathlib import Path

from .summary import HEADLINE, Group


def plot_summary(groups: list[Group], path: str | Path) -> None:
    """Pass rate and headline metrics (mean, error bar = std) against each swept value."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..results import temp_beside

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
                ax.set_ylabel("passed [%]")
            elif panel.endswith("goal_reached"):  # a rate, like the pass rate
                ax.bar(x, [100 * g.metrics[panel].mean if panel in g.metrics else 0.0
                           for g in mine], color="tab:blue")
                ax.set_ylim(0, 100)
                ax.set_ylabel(f"{panel} [%]")
            else:
                means = [g.metrics[panel].mean if panel in g.metrics else math.nan for g in mine]
                stds = [g.metrics[panel].std if panel in g.metrics else 0.0 for g in mine]
                ax.errorbar(list(x), means, yerr=stds, fmt="o-", capsize=3)
                ax.set_ylabel(panel)
            ax.set_xticks(list(x), labels)
            ax.set_xlabel(key)
    fig.tight_layout()
    path = Path(path)
    tmp = temp_beside(path, path.suffix or ".png")
    try:
        fig.savefig(tmp)
        Path(tmp).replace(path)
    finally:
        plt.close(fig)
        Path(tmp).unlink(missing_ok=True)
