"""Per-robot measurements taken every tick, only when an expectation asks for them:
clearance (``min_clearance``) and forbidden regions (``never_enter``)."""
from __future__ import annotations

from typing import Any

import numpy as np
import pymunk

from pymunk_bot.geometry.footprint import Footprint
from pymunk_bot.geometry.plane import point_in_polygon

CLEARANCE_HORIZON = 10.0  # [m]; clearances beyond this read as this


class RobotMetrics:
    """Closest approach to anything and entries into ``never_enter`` regions.

    ``min_clearance`` is measured only when ``track_clearance`` is set; the query then looks no
    farther than the closest approach so far, so it costs little once something came near.
    ``shape_filter``: what the clearance query sees (default: the robot's own filter).
    ``navigation``: the robot's :class:`~pymunk_bot.outcomes.navigation.NavMetrics` when the run
    measures them (a crowd, or an expectation bounding one), updated with the rest."""

    def __init__(self, space: pymunk.Space, robot: Any, never_enter: list,
                 track_clearance: bool = True,
                 shape_filter: pymunk.ShapeFilter | None = None) -> None:
        self._space = space
        self._robot = robot
        self._filter = robot.shape.filter if shape_filter is None else shape_filter
        self.navigation: Any = None
        self._radius = robot.radius
        self._regions = [np.asarray(poly, dtype=float) for poly in never_enter]
        self.track_clearance = track_clearance
        self.min_clearance: float | None = CLEARANCE_HORIZON if track_clearance else None  # [m]
        self.entered: list[float | None] = [None] * len(self._regions)
        self.active = track_clearance or bool(self._regions)
        # A footprint other than a disc about the pose point: clearance of its outline points.
        footprint = getattr(robot.spec, "footprint", None)
        self._outline = None if footprint is None else outline_samples(footprint)

    def update(self, time: float) -> None:
        if self.navigation is not None:
            self.navigation.update(time)
        position = self._robot.body.position
        if self.min_clearance is not None and self._outline is not None:
            body = self._robot.body
            for point in self._outline:
                hit = self._space.point_query_nearest(body.local_to_world(point),
                                                      self.min_clearance, self._filter)
                if hit is not None and hit.distance < self.min_clearance:
                    self.min_clearance = max(0.0, hit.distance)
        elif self.track_clearance:
            reach = self.min_clearance + self._radius
            hit = self._space.point_query_nearest(position, reach, self._filter)
            if hit is not None:
                clearance = max(0.0, hit.distance - self._radius)
                if clearance < self.min_clearance:
                    self.min_clearance = clearance
        for i, region in enumerate(self._regions):
            if self.entered[i] is None and point_in_polygon(position, region):
                self.entered[i] = time


OUTLINE_SPACING = 0.02  # [m] between the outline points a footprint's clearance is measured at


def outline_samples(footprint: Footprint) -> list[tuple[float, float]] | None:
    """Points every OUTLINE_SPACING along a footprint's outline (robot frame), or None for a
    disc about the pose point (measured exactly from its centre)."""
    if footprint.points is None and footprint.center == (0.0, 0.0):
        return None
    outline = footprint.outline()
    out: list[tuple[float, float]] = []
    for a, b in zip(outline, np.roll(outline, -1, axis=0)):
        n = max(1, int(np.ceil(np.hypot(*(b - a)) / OUTLINE_SPACING)))
        out.extend((tuple(a + (b - a) * k / n) for k in range(n)))
    return out
