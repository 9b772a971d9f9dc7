"""Per-robot measurements taken every tick: clearance, forbidden regions."""
from __future__ import annotations

import numpy as np
import pymunk

from .geometry import point_in_polygon

CLEARANCE_HORIZON = 10.0  # [m]; clearances beyond this read as this


class RobotMetrics:
    """Closest approach to anything and entries into ``never_enter`` regions."""

    def __init__(self, space: pymunk.Space, robot, never_enter: list) -> None:
        self._space = space
        self._robot = robot
        self._filter = robot.shape.filter
        self._regions = [np.asarray(poly, dtype=float) for poly in never_enter]
        self.min_clearance = CLEARANCE_HORIZON  # [m] from the robot's surface
        self.entered: list[float | None] = [None] * len(self._regions)

    def update(self, time: float) -> None:
        position = self._robot.body.position
        hit = self._space.point_query_nearest(position, CLEARANCE_HORIZON, self._filter)
        if hit is not None:
            clearance = max(0.0, hit.distance - self._robot.radius)
            if clearance < self.min_clearance:
                self.min_clearance = clearance
        for i, region in enumerate(self._regions):
            if self.entered[i] is None and point_in_polygon(position, region):
                self.entered[i] = time
