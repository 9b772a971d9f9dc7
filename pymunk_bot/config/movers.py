"""Checks of things that move by themselves: obstacle ``motion`` paths and pedestrians."""
from __future__ import annotations

import math

import numpy as np

PATH_START_TOLERANCE = 1e-3  # [m] a box's or circle's path starts at its center within this


def _outside(points: np.ndarray, width: float, height: float) -> bool:
    return bool((points[:, 0] < -1e-9).any() or (points[:, 1] < -1e-9).any()
                or (points[:, 0] > width + 1e-9).any() or (points[:, 1] > height + 1e-9).any())


def check_mover(index: int, obstacle, scenario) -> None:
    """A scripted path stays inside the arena and starts at the obstacle; a pedestrian's start
    and goals lie inside the arena."""
    from .semantics import SemanticError, obstacle_outline

    width, height = scenario.world.size
    if getattr(obstacle, "type", "") == "pedestrian":
        r = obstacle.radius
        for key, points in (("center", [obstacle.center]), ("goals", obstacle.goals)):
            for k, (x, y) in enumerate(points):
                if not (r <= x <= width - r and r <= y <= height - r):
                    loc = ("obstacles", index, key) + (() if key == "center" else (k,))
                    raise SemanticError(loc, f"pedestrian of radius {r:g} at ({x:g}, {y:g}) is "
                                             f"not inside the arena [0, {width:g}] x [0, {height:g}]")
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
            extent = np.array([point - r, point + r])
        elif spin:  # any angle: the disc about the centre that holds the outline
            centre = outline.mean(axis=0) + shift
            r = float(np.hypot(*(outline - outline.mean(axis=0)).T).max())
            extent = np.array([centre - r, centre + r])
        else:
            extent = outline + shift
        if _outside(extent, width, height):
            raise SemanticError(loc + ("path", k), f"({point[0]:g}, {point[1]:g}) takes the "
                                f"obstacle out of the arena [0, {width:g}] x [0, {height:g}]")
