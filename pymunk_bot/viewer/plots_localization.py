"""`pymunk-bot plot LOG --kind localization`: the localizer's estimate against the truth.

Two panels over time: the position error [m] with the 95 % radius the filter claims (from its
covariance), and the heading error [deg] with its claimed 95 % band; a filter whose error
stays inside its own band is consistent.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.config.errors import ScenarioError

CHI2_2D_95 = 5.991  # chi^2 with 2 degrees of freedom at 95 %: the position error ellipse
Z_95 = 1.96  # the two-sided 95 % normal quantile: the heading band


def localization_figure(log, robot: str | None, Figure, colour, dpi: int):
    """A Figure with the position and heading error panels of every localizing robot."""
    tracks = getattr(log, "localization", {}) or {}
    names = [n for n in log.robot_names if n in tracks and (robot is None or n == robot)]
    if not names:
        which = f"robot '{robot}'" if robot else "no robot"
        raise ScenarioError("--kind", "", f"{which} in the log has a localizer (log a scenario "
                                          "whose robot has `localization:`, e.g. mcl_office)")
    fig = Figure(figsize=(9, 6), dpi=dpi, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    t = np.asarray(log.time, dtype=float)
    for name in names:
        j = log.robot_names.index(name)
        track = tracks[name]
        truth, est, cov = log.pose[:, j], track.estimate, track.covariance
        error = np.hypot(*(est[:, :2] - truth[:, :2]).T)
        heading = np.rad2deg(np.angle(np.exp(1j * (est[:, 2] - truth[:, 2]))))
        claimed = np.sqrt(CHI2_2D_95 * np.linalg.eigvalsh(cov[:, :2, :2])[:, -1].clip(0.0))
        band = np.rad2deg(Z_95 * np.sqrt(cov[:, 2, 2].clip(0.0)))
        c = colour(j)
        top.plot(t, error, color=c, label=f"{name}: |estimate - truth|")
        top.fill_between(t, 0.0, claimed, color=c, alpha=0.15, label=f"{name}: claimed 95 %")
        bottom.plot(t, heading, color=c, label=name)
        bottom.fill_between(t, -band, band, color=c, alpha=0.15)
    top.set_ylabel("position error [m]")
    top.set_ylim(bottom=0.0)
    top.legend(loc="upper right", fontsize="small")
    bottom.axhline(0.0, color="0.5", linewidth=0.8)
    bottom.set_ylabel("heading error [deg]")
    bottom.set_xlabel("time [s]")
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
    return fig
