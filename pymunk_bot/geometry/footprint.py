"""A robot's footprint as geometry (no pymunk): outline, convex pieces, the discs that bound it.

Everything is in the robot frame, whose origin is the pose point (an ackermann robot's rear-axle
middle). Clearance checks, start-pose checks, substeps and planners all read it from here.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Sequence

import numpy as np
import shapely

from pymunk_bot.geometry import plane as geo

CIRCLE_SIDES = 32  # polygon approximation of a disc footprint, for overlap checks


@dataclass(frozen=True)
class Footprint:
    """``kind`` "circle" (``center``, ``radius``) or "polygon" (``points``, counter-clockwise)."""

    kind: str
    center: tuple[float, float]  # [m] of the disc, or the outline's area centroid
    radius: float  # [m] the disc's; for polygons the circumscribed radius about ``center``
    points: np.ndarray | None  # (n, 2) outline [m], counter-clockwise; None for a disc

    @property
    def bounding_radius(self) -> float:
        """Radius of the smallest disc about the pose point that holds the footprint [m]."""
        if self.points is None:
            return math.hypot(*self.center) + self.radius
        return float(np.hypot(self.points[:, 0], self.points[:, 1]).max())

    @property
    def half_thickness(self) -> float:
        """Half the footprint's thinnest width [m] (what a wall must not skip over)."""
        if self.points is None:
            return self.radius
        return geo.thinness(self.points) / 2.0

    def outline(self) -> np.ndarray:
        """The outline as a polygon (a disc as a circumscribed 32-gon), robot frame [m]."""
        if self.points is not None:
            return self.points
        k = np.arange(CIRCLE_SIDES) * (2 * math.pi / CIRCLE_SIDES)
        r = self.radius / math.cos(math.pi / CIRCLE_SIDES)
        return np.column_stack([self.center[0] + r * np.cos(k), self.center[1] + r * np.sin(k)])

    def at(self, pose: Sequence[float] | np.ndarray) -> np.ndarray:
        """The outline placed at a world pose (x, y, theta) [m]."""
        return transform(self.outline(), pose)

    def covering_discs(self, spacing: float) -> tuple[np.ndarray, np.ndarray]:
        """(centres (k, 2) [m], radii (k,) [m]) of discs whose union holds the footprint.

        Planners check these against a clearance grid: a disc of radius r is free where the
        clearance at its centre is at least r. Discs sit along the footprint's long axis, at
        most ``spacing`` apart, each just large enough to cover its slice."""
        if self.points is None:
            return np.array([self.center]), np.array([self.radius])
        return _discs(self.points.tobytes(), len(self.points), float(spacing))


@lru_cache(maxsize=256)
def _discs(raw: bytes, n: int, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    points = np.frombuffer(raw).reshape(n, 2)
    centred = points - points.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    axis = axes[0]
    normal = np.array([-axis[1], axis[0]])
    along = points @ axis
    lo, hi = float(along.min()), float(along.max())
    count = max(1, math.ceil((hi - lo) / spacing))
    step = (hi - lo) / count
    across = points @ normal
    mid = 0.5 * (across.min() + across.max())
    reach = float(across.max() - across.min()) + 1.0  # [m] a slab wider than the footprint
    angle = math.atan2(axis[1], axis[0])
    shape = geo.polygon(points)
    centres, radii = [], []
    for k in range(count):
        centre = (lo + (k + 0.5) * step) * axis + mid * normal
        # The footprint cut to the slab [a - step/2, a + step/2] along the axis: its farthest
        # corner (a vertex or where the outline crosses the slab's ends) bounds the disc.
        slab = geo.polygon(geo.box_corners(centre, (step, reach), angle))
        sample = shapely.get_coordinates(shapely.intersection(shape, slab))
        centres.append(centre)
        radii.append(float(np.hypot(*((sample if len(sample) else points) - centre).T).max()))
    return np.array(centres), np.array(radii)


def drawn_outline(footprint: "Footprint | None") -> np.ndarray | None:
    """The outline views draw (robot frame), or None for a plain disc about the pose point."""
    if footprint is None or (footprint.points is None and footprint.center == (0.0, 0.0)):
        return None
    return footprint.outline()


def transform(points: np.ndarray, pose: Sequence[float] | np.ndarray) -> np.ndarray:
    """Robot-frame points [m] -> world frame at ``pose`` (x, y, theta)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + (pose[0], pose[1])


def of_robot(rc: Any) -> Footprint:
    """The footprint a robot config describes (a disc of ``radius`` when it names none)."""
    section = getattr(rc, "footprint", None)
    if section is None:
        return Footprint("circle", (0.0, 0.0), float(rc.radius), None)
    if section.type == "circle":
        cx, cy = section.center
        return Footprint("circle", (float(cx), float(cy)), float(section.radius), None)
    if section.type == "box":
        points = geo.box_corners(section.center, section.size)
    else:
        points = np.asarray(section.points, dtype=float)
        if geo.signed_area(points) < 0:
            points = points[::-1].copy()
    centroid = polygon_centroid(points)
    radius = float(np.hypot(*(points - centroid).T).max())
    return Footprint("polygon", centroid, radius, points)


def polygon_centroid(points: np.ndarray) -> tuple[float, float]:
    """Area centroid of a simple polygon [m]."""
    centre = shapely.get_coordinates(shapely.centroid(geo.polygon(points)))
    if not len(centre):
        return (math.nan, math.nan)
    return (float(centre[0, 0]), float(centre[0, 1]))
