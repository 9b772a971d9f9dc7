"""Obstacle configs -> pymunk bodies and shapes (concave polygons split into convex pieces)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pymunk
from pymunk import autogeometry

from pymunk_bot.geometry import plane as geo
from pymunk_bot.physics import settings as physics
from pymunk_bot.geometry.footprint import Footprint
from pymunk_bot.config.schema import BoxObstacle, CircleObstacle, WallObstacle


@dataclass
class Obstacle:
    """One obstacle in the world: its config, body (static body for fixed ones) and shapes."""

    config: object
    body: pymunk.Body
    shapes: list[pymunk.Shape]

    @property
    def movable(self) -> bool:
        """It moves: pushed (a dynamic body), scripted (kinematic) or walking (a pedestrian)."""
        return self.body.body_type != pymunk.Body.STATIC

    @property
    def pushable(self) -> bool:
        """A dynamic body that contacts push around (crates, pedestrians)."""
        return self.body.body_type == pymunk.Body.DYNAMIC


def convex_pieces(points: np.ndarray) -> list[np.ndarray]:
    """Convex pieces of a simple polygon outline of either winding."""
    outline = points if geo.signed_area(points) > 0 else points[::-1]
    closed = [tuple(p) for p in outline] + [tuple(outline[0])]
    pieces = autogeometry.convex_decomposition(closed, 0.0)
    return [np.array([(v.x, v.y) for v in piece[:-1]]) for piece in pieces]


def _local_outlines(config: Any) -> tuple[np.ndarray, float, list[np.ndarray]]:
    """(centre, angle, convex outlines relative to the centre) of a polygonal obstacle."""
    if isinstance(config, BoxObstacle):
        return np.asarray(config.center), config.angle, [geo.box_corners((0, 0), config.size)]
    if isinstance(config, WallObstacle):
        corners = geo.wall_corners(config.start, config.end, config.thickness)
        return np.zeros(2), 0.0, [corners]
    points = np.asarray(config.points, dtype=float)
    centre = points.mean(axis=0)
    return centre, 0.0, [piece - centre for piece in convex_pieces(points)]


def build_obstacle(space: pymunk.Space, config: Any) -> Obstacle:
    """Add one obstacle to the space."""
    scripted = getattr(config, "motion", None) is not None
    movable = getattr(config, "movable", False) or scripted
    outlines: list[np.ndarray]  # convex pieces in the body frame (none for a circle)
    if isinstance(config, CircleObstacle):
        centre, angle, outlines = np.asarray(config.center), 0.0, []
    else:
        centre, angle, outlines = _local_outlines(config)
    if scripted:  # follows its path whatever is in the way (see actors/motion.py)
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body.position = tuple(centre)
        body.angle = angle
    elif movable:
        body = pymunk.Body()
        body.position = tuple(centre)
        body.angle = angle
    else:
        body = space.static_body
    shapes: list[pymunk.Shape] = []
    if isinstance(config, CircleObstacle):
        offset = (0, 0) if movable else tuple(centre)
        shapes.append(pymunk.Circle(body, config.radius, offset))
    else:
        for outline in outlines:
            if movable:
                shapes.append(pymunk.Poly(body, [tuple(p) for p in outline]))
            else:
                transform = pymunk.Transform.translation(*centre).rotated(angle)
                shapes.append(pymunk.Poly(body, [tuple(p) for p in outline], transform))
    for shape in shapes:
        shape.friction = config.friction
        shape.collision_type = physics.MOVABLE if movable else physics.STATIC
    if scripted:
        space.add(body, *shapes)
    elif movable:
        total_area = sum(s.area for s in shapes)
        for shape in shapes:
            shape.mass = config.mass * shape.area / total_area
        space.add(body, *shapes)
        physics.ground_friction(space, body, config.ground_friction)
    else:
        space.add(*shapes)
    return Obstacle(config, body, shapes)


def footprint_shapes(body: pymunk.Body, footprint: Footprint, mass: float) -> list[pymunk.Shape]:
    """A robot footprint's shapes on ``body`` (concave outlines as convex pieces), with
    ``mass`` [kg] spread by area, so pymunk puts the centre of gravity at the centroid."""
    if footprint.points is None:
        shapes: list[pymunk.Shape] = [pymunk.Circle(body, footprint.radius, footprint.center)]
    else:
        shapes = [pymunk.Poly(body, [tuple(p) for p in piece])
                  for piece in convex_pieces(footprint.points)]
    total_area = sum(s.area for s in shapes)
    for shape in shapes:
        shape.mass = mass * shape.area / total_area
    return shapes
