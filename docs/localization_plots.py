"""Make the figures of docs/localization.md (run from the repository root):

    python docs/localization_plots.py [mcl global slam_ekf loop]  -> docs/img/localization_*.png
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent / "img"


def _map(ax, grid) -> None:
    shown = np.where(grid.data < 0, 0.5, 1.0 - grid.data / 100.0)
    x0, y0 = grid.origin
    w, h = grid.size
    ax.imshow(shown, origin="lower", cmap="gray", vmin=0, vmax=1, extent=(x0, x0 + w, y0, y0 + h))
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def mcl_figure(plt) -> None:
    from pymunk_bot import Simulation
    from bench import localization_worlds as worlds
    from pymunk_bot.localization import MclConfig, MclLocalizer
    from pymunk_bot.localization.trial import make_context, run_trial
    from pymunk_bot.maps.rasterize import scenario_grid

    sim = Simulation.from_dict(worlds.office_scenario(0))
    grid = scenario_grid(sim.config, 0.05)
    odometry = []
    loc = MclLocalizer(MclConfig(sigma_hit=0.05, update_min_d=0.05, update_min_a=0.05),
                       make_context(sim, "r1", 0, grid))
    trial = run_trial(sim, loc, worlds.OFFICE_ROUTE, 120.0,
                      on_step=lambda s, _: odometry.append(s.robots["r1"].odometry.pose.copy()))
    t, truth, est = trial.arrays()
    odometry = np.asarray(odometry)
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8), gridspec_kw={"width_ratios": [1.2, 1]})
    _map(a, grid)
    a.plot(truth[:, 0], truth[:, 1], "g-", lw=2, label="truth")
    a.plot(est[:, 0], est[:, 1], "b--", lw=1, label="MCL estimate")
    a.plot(odometry[:, 0], odometry[:, 1], "r:", lw=1, label="odometry alone")
    a.set_xlim(-0.5, 10.5)
    a.set_ylim(-0.5, 8.5)
    a.legend(loc="upper right", fontsize=7)
    err = np.hypot(*(truth[:, :2] - est[:, :2]).T)
    b.plot(t, 100 * err, "b-", lw=1, label="position error [cm]")
    dh = np.rad2deg(np.abs((est[:, 2] - truth[:, 2] + np.pi) % (2 * np.pi) - np.pi))
    b.plot(t, dh, "m-", lw=0.8, label="heading error [deg]")
    b.axhline(5, color="b", ls=":", lw=0.8)
    b.axhline(2, color="m", ls=":", lw=0.8)
    b.set_xlabel("time [s]")
    b.legend(fontsize=7)
    fig.suptitle("MCL in the office with drifting odometry")
    fig.tight_layout()
    fig.savefig(OUT / "localization_mcl.png", dpi=70)


def global_figure(plt) -> None:
    from pymunk_bot import Simulation
    from bench import localization_worlds as worlds
    from pymunk_bot.localization import MclConfig, MclLocalizer
    from pymunk_bot.localization.trial import make_context, run_trial

    start, route = worlds.route_from(worlds.ROS_ROUTE, worlds.ROS_START, 2)
    data, grid = worlds.ros_map_world(0, start=start)
    sim = Simulation.from_dict(data)
    loc = MclLocalizer(MclConfig(initial="global", max_particles=5000, recovery_alpha_slow=0.001,
                                 recovery_alpha_fast=0.1), make_context(sim, "r1", 0, grid))
    snaps = {}
    wanted = [0.0, 2.0, 5.0, 10.0]

    def grab(s, l):
        for w in wanted:
            if w not in snaps and s.time >= w:
                snaps[w] = (l.particles.copy(), s.robots["r1"].pose.copy())

    grab(sim, loc)
    run_trial(sim, loc, route, 10.5, drive_on="truth", on_step=grab)
    fig, axes = plt.subplots(1, 4, figsize=(12, 3.2))
    for ax, w in zip(axes, wanted):
        particles, pose = snaps[w]
        _map(ax, grid)
        ax.plot(particles[:, 0], particles[:, 1], "r.", ms=1)
        ax.plot(pose[0], pose[1], "go", ms=6)
        ax.set_title(f"t = {w:g} s, {particles.shape[0]} particles", fontsize=9)
    fig.suptitle("Global localization on a ROS-style map (grey: unknown)")
    fig.tight_layout()
    fig.savefig(OUT / "localization_global.png", dpi=60)


def slam_ekf_figure(plt) -> None:
    from scipy.stats import chi2

    from pymunk_bot import Simulation
    from bench import localization_worlds as worlds
    from pymunk_bot.localization import EkfConfig, EkfLocalizer, SlamConfig, SlamLocalizer
    from pymunk_bot.localization.se2 import wrap
    from pymunk_bot.localization.trial import make_context, run_trial

    sim = Simulation.from_dict(worlds.office_scenario(0))
    slam = SlamLocalizer(SlamConfig(), make_context(sim, "r1", 0, None))
    run_trial(sim, slam, worlds.OFFICE_ROUTE, 120.0)
    data, grid = worlds.ros_map_world(1)
    sim = Simulation.from_dict(data)
    ekf = EkfLocalizer(EkfConfig(), make_context(sim, "r1", 1, grid))
    nees, times = [], []

    def record(s, l):
        r = s.robots["r1"]
        if abs(r.lidar.latest.time - s.time) < 1e-9:
            e = l.pose - r.pose
            e[2] = wrap(e[2])
            nees.append(float(e @ np.linalg.solve(l.covariance, e)))
            times.append(s.time)

    run_trial(sim, ekf, worlds.ROS_ROUTE, 120.0, on_step=record)
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8), gridspec_kw={"width_ratios": [1.2, 1]})
    _map(a, slam.grid)
    kf = np.asarray(slam.keyframes)
    a.plot(kf[:, 0], kf[:, 1], "b.-", ms=2, lw=0.6, label="keyframes")
    for i, j in slam.loop_closures:
        a.plot(kf[[i, j], 0], kf[[i, j], 1], "r-", lw=1.5)
    a.plot([], [], "r-", label="loop closures")
    a.legend(loc="upper right", fontsize=7)
    a.set_title("SLAM: the map it built", fontsize=9)
    b.semilogy(times, nees, "k.", ms=1.5)
    b.axhline(chi2.ppf(0.025, 3), color="g", lw=0.8)
    b.axhline(chi2.ppf(0.975, 3), color="g", lw=0.8, label="95 % band, chi2(3)")
    b.set_xlabel("time [s]")
    b.set_ylabel("NEES")
    b.legend(fontsize=7)
    b.set_title("EKF consistency on the ROS-style map", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "localization_slam_ekf.png", dpi=70)


def loop_closure_figure(plt) -> None:
    """SLAM in Nav2's warehouse, there and back (robustness bench, slam_revisit seed 2, typical
    odometry): its keyframes without loop closures and with them, against the truth."""
    from bench.localization_robustness import run_one

    runs = {}
    for name, settings in (("without", {"loop_min_travel": 100.0}), ("with", None)):
        def keep(sim, truth, name=name):
            runs[name] = (sim.robots["r1"].localizer, truth)
        out = run_one("slam_revisit", "warehouse", "typical", 2, settings, on_finish=keep)
        if out is None:
            print("the warehouse map is not beside the checkout: no loop-closure figure")
            return
        runs[name] += (out,)
    fig, axes = plt.subplots(1, 2, figsize=(10, 5.2), sharex=True, sharey=True)
    for ax, name in zip(axes, ("without", "with")):
        slam, truth, out = runs[name]
        kf = np.asarray(slam.keyframes)
        _map(ax, slam.grid)
        ax.plot(truth[:, 0], truth[:, 1], "g-", lw=1.2, label="truth")
        ax.plot(kf[:, 0], kf[:, 1], "r-", lw=1.0, label="SLAM keyframes (final)")
        for c in slam.closures:
            ax.plot(kf[[c.old, c.new], 0], kf[[c.old, c.new], 1], "b-", lw=0.8)
        if slam.closures:
            ax.plot([], [], "b-", label=f"loop closures ({len(slam.closures)})")
        ax.set_title(f"{name} loop closure: ATE {100 * out.ate:.1f} cm, "
                     f"map precision {out.map_precision:.2f}")
        ax.set_xlim(-14, 10)
        ax.set_ylim(-18, 0)
        ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "localization_loop_closure.png", dpi=70)


FIGURES = {"mcl": mcl_figure, "global": global_figure, "slam_ekf": slam_ekf_figure,
           "loop": loop_closure_figure}


def main() -> None:
    """``python docs/localization_plots.py [mcl global slam_ekf loop]``: those figures (all
    of them by default)."""
    import sys

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    OUT.mkdir(exist_ok=True)
    names = sys.argv[1:] or list(FIGURES)
    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        print(f"localization_plots.py: unknown figure {', '.join(unknown)}; valid: "
              f"{', '.join(FIGURES)}", file=sys.stderr)
        raise SystemExit(2)
    for name in names:
        FIGURES[name](plt)


if __name__ == "__main__":
    main()
