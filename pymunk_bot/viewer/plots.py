"""Figures from run logs: trajectories over the map, speeds, LiDAR ranges over time.

matplotlib is imported inside the functions and only its object-oriented API is used (a
Figure on an Agg canvas), so nothing here changes the user's pyplot backend or state.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.runlog import RunLog
from pymunk_bot.viewer import palette as pal

KINDS = ("all", "map", "speed", "ranges", "localization")
FORMATS = (".png", ".pdf", ".svg")
DPI = 120


def _matplotlib():
    try:
        from matplotlib.figure import Figure
        from matplotlib.patches import Circle, Polygon
    except ImportError:
        raise ScenarioError("plot", "", "matplotlib is not installed "
                                        "(pip install matplotlib)") from None
    return Figure, Circle, Polygon


def robot_colour(index: int) -> str:
    """The robot's colour, as in the viewer."""
    return pal.hex_colour(pal.robot_colour(index))


def make_figure(log: RunLog, kind: str = "all", robot: str | None = None):
    """A matplotlib Figure of ``kind`` ("all", "map", "speed", "ranges" or "localization")."""
    if kind not in KINDS:
        raise ValueError(f"unknown plot kind '{kind}'; valid: {', '.join(KINDS)}")
    names = log.robot_names
    if robot is not None and robot not in names:
        raise ScenarioError("--robot", "", f"no robot '{robot}' in the log; it has "
                                           f"{', '.join(names)}")
    Figure, _, _ = _matplotlib()
    width, height = log.size
    scanned = has_scans(log, robot)
    if kind == "ranges" and not scanned:
        which = f"robot '{robot}'" if robot is not None else "any robot"
        raise ScenarioError("--kind", "", f"ranges: the log has no LiDAR scans of {which} "
                                          "(give the robot a 'lidar' and run again)")
    if kind == "localization":  # estimate vs truth: viewer/plots_localization.py
        from pymunk_bot.viewer.plots_localization import localization_figure

        fig = localization_figure(log, robot, Figure, robot_colour, DPI)
    elif kind == "map":
        fig = Figure(figsize=_map_figsize(width, height), dpi=DPI, layout="constrained")
        draw_map(fig.add_subplot(), log, robot)
    elif kind == "speed":
        fig = Figure(figsize=(8, 4), dpi=DPI, layout="constrained")
        draw_speed(fig.add_subplot(), log, robot)
    elif kind == "ranges":
        fig = Figure(figsize=(8, 6), dpi=DPI, layout="constrained")
        top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
        draw_scan_image(top, log, robot)
        draw_ranges(bottom, log, robot)
    elif scanned:
        fig = Figure(figsize=(13, 6), dpi=DPI, layout="constrained")
        grid = fig.add_gridspec(2, 2, width_ratios=(1.4, 1))
        draw_map(fig.add_subplot(grid[:, 0]), log, robot)
        draw_speed(fig.add_subplot(grid[0, 1]), log, robot)
        draw_ranges(fig.add_subplot(grid[1, 1]), log, robot)
    else:  # no LiDAR: the speed plot takes the whole right column, no empty panel
        fig = Figure(figsize=(13, 6), dpi=DPI, layout="constrained")
        grid = fig.add_gridspec(1, 2, width_ratios=(1.4, 1))
        draw_map(fig.add_subplot(grid[0, 0]), log, robot)
        draw_speed(fig.add_subplot(grid[0, 1]), log, robot)
    fig.suptitle(f"{log.meta['scenario']} (seed {log.meta['seed']}), "
                 f"{float(log.time[-1]):.1f} s simulated")
    return fig


def has_scans(log: RunLog, robot: str | None = None) -> bool:
    """True when the log holds at least one LiDAR scan of the chosen robot(s)."""
    return any(len(log.scans[log.robot_names[i]].time) for i in _chosen(log, robot)
               if log.robot_names[i] in log.scans)


def save_plot(log: RunLog, path: str | Path, kind: str = "all", robot: str | None = None) -> None:
    """Draw ``kind`` and write it to ``path`` (.png, .pdf or .svg), atomically."""
    import io

    from pymunk_bot.outcomes.results import write_atomic

    path = Path(path)
    fig = make_figure(log, kind, robot)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=path.suffix.lower().lstrip("."), dpi=DPI)
    write_atomic(path, buffer.getvalue())


def _map_figsize(width: float, height: float) -> tuple[float, float]:
    aspect = height / width
    return (8.0, max(3.0, min(10.0, 8.0 * aspect + 0.8)))


def _chosen(log: RunLog, robot: str | None) -> list[int]:
    return [i for i, n in enumerate(log.robot_names) if robot is None or n == robot]


def draw_map(ax, log: RunLog, robot: str | None = None) -> None:
    """Obstacles (final positions, movable ones also at the start), true paths and odometry."""
    _, Circle, Polygon = _matplotlib()
    width, height = log.size
    x0, y0 = log.origin  # a ROS map's origin; (0, 0) for a box arena
    ax.add_patch(Polygon([(x0, y0), (x0 + width, y0), (x0 + width, y0 + height), (x0, y0 + height)],
                         closed=True, facecolor=pal.hex_colour(pal.FLOOR), edgecolor="none",
                         zorder=0))
    for g in log.fixed_shapes():  # walls too: a map's walls lie inside the arena
        colour = pal.hex_colour(pal.WALL if g.wall else pal.STATIC)
        _shape_patch(ax, g.placed((0.0, 0.0, 0.0)), colour, Circle, Polygon,
                     edge=colour if g.wall else None)
    for k, shapes in enumerate(log.movable_shapes()):
        for g in shapes:
            _shape_patch(ax, g.placed(log.obstacle_pose[0, k]), "none", Circle, Polygon,
                         edge=pal.hex_colour(pal.MOVABLE), linestyle=":")
            _shape_patch(ax, g.placed(log.obstacle_pose[-1, k]), pal.hex_colour(pal.MOVABLE),
                         Circle, Polygon, edge=pal.hex_colour(pal.MOVABLE_EDGE))
    for i in _chosen(log, robot):
        name, colour = log.robot_names[i], robot_colour(i)
        true, odom = log.pose[:, i, :2], log.odometry[:, i, :2]
        ax.plot(true[:, 0], true[:, 1], color=colour, lw=2.0, label=f"{name} true", zorder=3)
        ax.plot(odom[:, 0], odom[:, 1], color=colour, lw=1.2, ls="--", alpha=0.8,
                label=f"{name} odometry", zorder=3)
        radius = float(log.meta["robots"][i]["radius"])
        ax.add_patch(Circle(tuple(true[0]), radius, facecolor="none", edgecolor=colour, lw=1.2,
                            zorder=4))
        ax.add_patch(Circle(tuple(true[-1]), radius, facecolor=colour, edgecolor="black",
                            lw=0.8, alpha=0.9, zorder=4))
        goals = log.goal[:, i]
        seen = {tuple(np.round(g, 9)) for g in goals if not np.isnan(g).any()}
        for gx, gy in sorted(seen):
            ax.plot(gx, gy, marker="x", ms=9, mew=2, color=colour, zorder=5)
    ax.set_xlim(x0, x0 + width)
    ax.set_ylim(y0, y0 + height)
    ax.set_aspect("equal")
    ax.set_facecolor(pal.hex_colour(pal.WALL))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("trajectories: true (solid) and odometry (dashed)")
    ax.legend(loc="best", fontsize="small", framealpha=0.9)


def _shape_patch(ax, shape, face, Circle, Polygon, edge=None, linestyle="-") -> None:
    edge = edge or pal.hex_colour(pal.STATIC_EDGE)
    if shape.kind == "circle":
        ax.add_patch(Circle(tuple(shape.points[0]), shape.radius, facecolor=face, edgecolor=edge,
                            ls=linestyle, zorder=1))
    elif shape.kind == "segment":
        ax.plot(shape.points[:, 0], shape.points[:, 1], color=edge,
                lw=max(1.0, 2 * shape.radius * 72), zorder=1)
    else:
        ax.add_patch(Polygon(shape.points, closed=True, facecolor=face, edgecolor=face
                             if face != "none" else edge, ls=linestyle, lw=1.0, zorder=1))


def draw_speed(ax, log: RunLog, robot: str | None = None) -> None:
    """True forward speed against the commanded one, over time."""
    t = log.time
    for i in _chosen(log, robot):
        colour = robot_colour(i)
        ax.plot(t, log.velocity[:, i, 0], color=colour, lw=1.6,
                label=f"{log.robot_names[i]} true")
        ax.plot(t, log.command[:, i].mean(axis=1), color=colour, lw=1.0, ls="--",
                label=f"{log.robot_names[i]} commanded")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("forward speed [m/s]")
    ax.set_title("speed")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize="small")


def draw_ranges(ax, log: RunLog, robot: str | None = None) -> None:
    """The closest LiDAR return of each scan, over time."""
    drawn = False
    for i in _chosen(log, robot):
        scans = log.scans.get(log.robot_names[i])
        if scans is None or len(scans.time) == 0:
            continue
        closest = scans.ranges.min(axis=1)
        ax.plot(scans.time, closest, color=robot_colour(i), lw=1.4,
                label=log.robot_names[i])
        drawn = True
    ax.set_xlabel("time [s]")
    ax.set_ylabel("closest return [m]")
    ax.set_title("LiDAR: nearest obstacle")
    ax.grid(True, alpha=0.3)
    if drawn:
        ax.set_ylim(bottom=0)
        ax.legend(loc="best", fontsize="small")
    else:
        ax.text(0.5, 0.5, "no LiDAR in this log", ha="center", va="center",
                transform=ax.transAxes)


def draw_scan_image(ax, log: RunLog, robot: str | None = None) -> None:
    """Every beam's range over time as an image (time across, beam angle up)."""
    index = next((i for i in _chosen(log, robot)
                  if log.robot_names[i] in log.scans and len(log.scans[log.robot_names[i]].time)),
                 None)
    if index is None:
        ax.text(0.5, 0.5, "no LiDAR in this log", ha="center", va="center",
                transform=ax.transAxes)
        return
    scans = log.scans[log.robot_names[index]]
    angles = np.degrees(scans.angles)
    t = scans.time
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    da = float(np.median(np.diff(angles))) if len(angles) > 1 else 1.0
    image = ax.imshow(scans.ranges.T, origin="lower", aspect="auto", cmap="cividis",
                      extent=(t[0] - dt / 2, t[-1] + dt / 2, angles[0] - da / 2,
                              angles[-1] + da / 2), vmin=0, vmax=scans.max_range,
                      interpolation="nearest")
    ax.figure.colorbar(image, ax=ax, label="range [m]")
    ax.set_ylabel("beam angle [deg]")
    ax.set_title(f"LiDAR ranges of {log.robot_names[index]}")
