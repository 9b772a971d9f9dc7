"""Several pymunk Spaces cast against as the one Space that would hold all their shapes.

A world whose robots nothing can reach step in a second Space (physics/apart.py) keeps those
robots' shapes there, with their bodies; its LiDARs must still see them. Each shape's own
segment and point tests do not depend on the Space it is in, and pymunk's first hit and
nearest shape over one Space are the least of its shapes' answers, so over several Spaces
they are the least of each Space's: the same alpha, the same distance.
"""
from __future__ import annotations

from typing import Sequence

import pymunk


class Spaces:
    """``spaces`` as one, for :class:`~pymunk_bot.sensors.raycast.RayCaster`: their shapes,
    bodies, and the two queries it asks pymunk."""

    def __init__(self, spaces: Sequence[pymunk.Space]) -> None:
        self.spaces = tuple(spaces)

    @property
    def shapes(self) -> list[pymunk.Shape]:
        """Every Space's shapes, Space after Space."""
        return [shape for space in self.spaces for shape in space.shapes]

    def segment_query_first(self, start: tuple[float, float], end: tuple[float, float],
                            radius: float, shape_filter: pymunk.ShapeFilter
                            ) -> pymunk.SegmentQueryInfo | None:
        """The first shape the segment meets, in any Space (the least alpha)."""
        first = None
        for space in self.spaces:
            hit = space.segment_query_first(start, end, radius, shape_filter)
            if hit is not None and (first is None or hit.alpha < first.alpha):
                first = hit
        return first

    def point_query_nearest(self, point: tuple[float, float], max_distance: float,
                            shape_filter: pymunk.ShapeFilter) -> pymunk.PointQueryInfo | None:
        """The nearest shape within ``max_distance`` [m] of ``point``, in any Space."""
        nearest = None
        for space in self.spaces:
            hit = space.point_query_nearest(point, max_distance, shape_filter)
            if hit is not None and (nearest is None or hit.distance < nearest.distance):
                nearest = hit
        return nearest
