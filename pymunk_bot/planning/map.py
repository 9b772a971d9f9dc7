"""The map a navigation controller is given: the arena and the obstacles the scenario file lists.

A controller never sees the simulation. What it may know in advance is what a real robot's
prebuilt map would hold: the arena walls and the fixed obstacles. Movable obstacles (crates) are
kept apart, flagged ``movable``: they may have been pushed since the file was written, so the
planner leaves them out unless a controller asks for them (``navigate``'s ``map_movable``).
Obstacles with a scripted ``motion`` and pedestrians are never on the map.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config.schema import CircleObstacle, ScenarioConfig
from ..config.semantics import obstacle_outline


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

    The free interior of the arena is ``[0, width] x [0, height]``; everything outside is wall.
    """

    size: tuple[float, float]
    polygons: tuple[MapPolygon, ...] = ()
    circles: tuple[MapCircle, ...] = ()

    @classmethod
    def from_scenario(cls, config: ScenarioConfig) -> "MapInfo":
        """The map of a scenario's arena and obstacles (movable ones flagged)."""
        polygons: list[MapPolygon] = []
        circles: list[MapCircle] = []
        for obstacle in config.obstacles:
            if getattr(obstacle, "motion", None) is not None or obstacle.type == "pedestrian":
                continue  # things that move by themselves are never on a map
            movable = bool(getattr(obstacle, "movable", False))
            if isinstance(obstacle, CircleObstacle):
                circles.append(MapCircle(tuple(obstacle.center), obstacle.radius, movable))
            else:
                outline = np.asarray(obstacle_outline(obstacle), dtype=float)
                outline.setflags(write=False)
                polygons.append(MapPolygon(outline, movable))
        return cls(tuple(config.world.size), tuple(polygons), tuple(circles))

    def without_movable(self) -> "MapInfo":
        """The same map with the movable obstacles left out."""
        return MapInfo(self.size, tuple(p for p in self.polygons if not p.movable),
                       tuple(c for c in self.circles if not c.movable))
