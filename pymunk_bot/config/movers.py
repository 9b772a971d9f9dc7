"""Checks of things that move by themselves: obstacle ``motion`` paths and pedestrians."""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.config.errors import SemanticError
from pymunk_bot.config.outlines import obstacle_outline

PATH_START_TOLERANCE = 1e-3  # [m] a box's or circle's path starts at its center within this


def _outside(points: np.ndarray, extent: tuple[float, float, float, float]) -> bool:
    """Whether any of ``points`` (n, 2) lies outside ``extent`` (x0, y0, x1, y1) [m]."""
    x0, y0, x1, y1 = extent
    return bool((points[:, 0] < x0 - 1e-9).any() or (points[:, 1] < y0 - 1e-9).any()
                or (points[:, 0] > x1 + 1e-9).any() or (points[:, 1] > y1 + 1e-9).any())


def _span(extent: tuple[float, float, float, float]) -> str:
    x0, y0, x1, y1 = extent
    return f"[{x0:g}, {x1:g}] x [{y0:g}, {y1:g}]"


def check_mover(index: int, obstacle, scenario) -> None:
    """A scripted path stays inside the arena and starts at the obstacle; a pedestrian's start
    and goals lie inside the arena (a map's arena where its ``origin`` puts it)."""
    extent = scenario.world.extent  # (x0, y0, x1, y1) [m]
    x0, y0, x1, y1 = extent
    if getattr(obstacle, "type", "") == "pedestrian":
        r = obstacle.radius
        for key, points in (("center", [obstacle.center]), ("goals", obstacle.goals)):
            for k, (x, y) in enumerate(points):
                if not (x0 + r <= x <= x1 - r and y0 + r <= y <= y1 - r):
                    loc = ("obstacles", index, key) + (() if key == "center" else (k,))
                    raise SemanticError(loc, f"pedestrian of radius {r:g} at ({x:g}, {y:g}) is "
                                             f"not inside the arena {_span(extent)}")
        return
    motion = getattr(obstacle, "motion", None)
    if motion is None:
        return
    loc = ("obstacles", index, "motion")
    if getattr(obstacle, "movable", False):
        raise SemanticError(loc, "a scripted obstacle cannot also be movable (set one of the two)")
    path = np.asarray(motion.path, dtype=float)
    if obstacle.type in ("box", "circle") and math.dist(path[0], obstacle.center) > PATH_START_TOLERANCE:
        raise SemanticError(loc + ("path", 0), f"the path must start at the obstacle's center "
                                               f"{tuple(obstacle.center)} (got {tuple(path[0])})")
    if np.hypot(*np.diff(path, axis=0).T).sum() < 1e-9:
        raise SemanticError(loc + ("path",), "the path has zero length")
    outline = obstacle_outline(obstacle)
    spin = motion.angular_speed != 0.0
    for k, point in enumerate(path):
        shift = point - path[0]
        if outline is None:
            r = obstacle.radius
            reach = np.array([point - r, point + r])
        elif spin:  # any angle: the disc about the centre that holds the outline
            centre = outline.mean(axis=0) + shift
            r = float(np.hypot(*(outline - outline.mean(axis=0)).T).max())
            reach = np.array([centre - r, centre + r])
        else:
            reach = outline + shift
        if _outside(reach, extent):
            raise SemanticError(loc + ("path", k), f"({point[0]:g}, {point[1]:g}) takes the "
                                f"obstacle out of the arena {_span(extent)}")
