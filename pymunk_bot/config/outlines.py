"""What obstacles and robot footprints occupy, from their config sections (no pymunk): the
outlines, distances and overlaps the scenario checks share."""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.geometry import plane as geo
from pymunk_bot.geometry.footprint import transform
from pymunk_bot.config.schema import BoxObstacle, PolygonObstacle, WallObstacle


def obstacle_outline(obstacle) -> np.ndarray | None:
    """Polygon outline of an obstacle [m], or None for circles. A plugin's obstacle kind gives
    its own through an ``outline()`` method."""
    if hasattr(obstacle, "outline"):
        return np.asarray(obstacle.outline(), dtype=float)
    if isinstance(obstacle, BoxObstacle):
        return geo.box_corners(obstacle.center, obstacle.size, obstacle.angle)
    if isinstance(obstacle, WallObstacle):
        return geo.wall_corners(obstacle.start, obstacle.end, obstacle.thickness)
    if isinstance(obstacle, PolygonObstacle):
        return np.asarray(obstacle.points, dtype=float)
    return None


def is_round(obstacle) -> bool:
    """A disc: a circle obstacle or a pedestrian (``center``, ``radius``)."""
    return getattr(obstacle, "type", "") in ("circle", "pedestrian")


def distance_to_obstacle(point, obstacle) -> float:
    """Distance from a point to an obstacle's surface (0 inside)."""
    if is_round(obstacle):
        return max(0.0, math.dist(point, obstacle.center) - obstacle.radius)
    return geo.distance_to_polygon(point, polygon_of(obstacle))


def polygon_of(obstacle) -> np.ndarray:
    """The outline of an obstacle that is not a circle (TypeError if it has none)."""
    outline = obstacle_outline(obstacle)
    if outline is None:
        raise TypeError(f"obstacle type '{obstacle.type}' has no outline: give its config "
                        "model an outline() method")
    return outline


def footprint_hits(footprint, pose, obstacle) -> bool:
    """True when a robot footprint at ``pose`` overlaps an obstacle (touching is fine)."""
    if footprint.points is None:
        centre = transform(np.array([footprint.center]), pose)[0]
        return distance_to_obstacle(centre, obstacle) < footprint.radius - 1e-9
    outline = footprint.at(pose)
    if is_round(obstacle):
        return geo.distance_to_polygon(obstacle.center, outline) < obstacle.radius - 1e-9
    other = obstacle_outline(obstacle)
    return other is not None and geo.polygons_overlap(outline, other)


def footprints_overlap(a, pose_a, b, pose_b) -> bool:
    """True when two robot footprints overlap at their poses."""
    if a.points is None and b.points is None:
        ca = transform(np.array([a.center]), pose_a)[0]
        cb = transform(np.array([b.center]), pose_b)[0]
        return math.dist(ca, cb) < a.radius + b.radius - 1e-9
    if a.points is None:
        a, pose_a, b, pose_b = b, pose_b, a, pose_a
    if b.points is None:
        cb = transform(np.array([b.center]), pose_b)[0]
        return geo.distance_to_polygon(cb, a.at(pose_a)) < b.radius - 1e-9
    return geo.polygons_overlap(a.at(pose_a), b.at(pose_b))
