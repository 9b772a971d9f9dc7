"""The map a navigation controller is given: the arena and the obstacles the scenario file lists.

A controller never sees the simulation. What it may know in advance is what a real robot's
prebuilt map would hold: the arena walls and the fixed obstacles. Movable obstacles (crates) are
kept apart, flagged ``movable``: they may have been pushed since the file was written, so the
planner leaves them out unless a controller asks for them (``navigate``'s ``map_movable``).
Obstacles with a scripted ``motion`` and pedestrians are never on the map.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pymunk_bot.config.schema import CircleObstacle, ScenarioConfig
from pymunk_bot.config.outlines import obstacle_outline
from pymunk_bot.maps.grid import OccupancyGrid


@dataclass(frozen=True)
class MapCircle:
    """A round obstacle: centre [m] and radius [m]."""

    center: tuple[float, float]
    radius: float
    movable: bool = False


@dataclass(frozen=True)
class MapPolygon:
    """A polygonal obstacle (box, wall or polygon; concave allowed): outline [m], shape (n, 2)."""

    points: np.ndarray
    movable: bool = False


@dataclass(frozen=True)
class MapInfo:
    """Arena size and obstacle geometry as the scenario describes it, in world metres.

    The free interior of the arena is ``origin + [0, width] x [0, height]``; everything outside
    is wall. With ``world.map``, the map's convex pieces are polygons and its segments are
    two-point polygons (or thin rectangles when they have a radius), and ``grid`` is a ROS
    map's own occupancy grid (unknown cells included), for whoever wants cells rather than shapes.
    """

    size: tuple[float, float]
    polygons: tuple[MapPolygon, ...] = ()
    circles: tuple[MapCircle, ...] = ()
    origin: tuple[float, float] = (0.0, 0.0)  # [m] lower-left corner of the arena
    grid: OccupancyGrid | None = None
    map_shapes: int = 0  # how many of the first ``polygons`` come from the map file

    @classmethod
    def from_scenario(cls, config: ScenarioConfig) -> "MapInfo":
        """The map of a scenario's arena and obstacles (movable ones flagged)."""
        polygons: list[MapPolygon] = []
        circles: list[MapCircle] = []
        geometry = config.world.map_geometry()
        if geometry is not None:
            polygons += map_polygons(geometry)
        from_map = len(polygons)
        for obstacle in config.obstacles:
            if getattr(obstacle, "motion", None) is not None or obstacle.type == "pedestrian":
                continue  # things that move by themselves are never on a map
            movable = bool(getattr(obstacle, "movable", False))
            if isinstance(obstacle, CircleObstacle):
                cx, cy = obstacle.center
                circles.append(MapCircle((cx, cy), obstacle.radius, movable))
            else:
                outline = np.asarray(obstacle_outline(obstacle), dtype=float)
                outline.setflags(write=False)
                polygons.append(MapPolygon(outline, movable))
        x0, y0, x1, y1 = config.world.extent
        return cls((x1 - x0, y1 - y0), tuple(polygons), tuple(circles), (x0, y0),
                   None if geometry is None else geometry.grid, from_map)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) [m] of the arena's interior."""
        return (self.origin[0], self.origin[1], self.origin[0] + self.size[0],
                self.origin[1] + self.size[1])

    def without_movable(self) -> "MapInfo":
        """The same map with the movable obstacles left out."""
        return replace(self, polygons=tuple(p for p in self.polygons if not p.movable),
                       circles=tuple(c for c in self.circles if not c.movable))  # map's first


def map_polygons(geometry: Any) -> list[MapPolygon]:
    """A map file's static geometry (:class:`~pymunk_bot.maps.outlines.MapGeometry`) as
    polygons: its convex pieces, and each segment as a two-point polygon (a line), or as the
    rectangle it sweeps when it has a radius (an SVG stroke)."""
    out = [MapPolygon(_frozen(piece)) for piece in geometry.polygons]
    for (x0, y0, x1, y1), radius in zip(geometry.segments.tolist(),
                                        geometry.segment_radius.tolist()):
        a, b = np.array([x0, y0]), np.array([x1, y1])
        length = float(np.hypot(*(b - a)))
        if radius <= 0 or length == 0:
            out.append(MapPolygon(_frozen(np.array([a, b]))))
            continue
        along = (b - a) / length * radius
        side = np.array([-along[1], along[0]])
        out.append(MapPolygon(_frozen(np.array([a - along - side, b + along - side,
                                                b + along + side, a - along + side]))))
    return out


def _frozen(points: np.ndarray) -> np.ndarray:
    points = np.array(points, dtype=float)
    points.setflags(write=False)
    return points
