"""Plain 2D geometry on numpy arrays (no pymunk): used to validate scenarios and build maps."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

Point = Sequence[float]


def box_corners(center: Point, size: Point, angle: float = 0.0) -> np.ndarray:
    """Corners of a rotated rectangle, counter-clockwise, shape (4, 2)."""
    hw, hh = size[0] / 2.0, size[1] / 2.0
    local = np.array([[-hw, -hh], [hw, -hh], [hw, hh], [-hw, hh]])
    c, s = math.cos(angle), math.sin(angle)
    return local @ np.array([[c, s], [-s, c]]) + np.asarray(center, dtype=float)


def wall_corners(start: Point, end: Point, thickness: float) -> np.ndarray:
    """The rectangle a wall segment of some thickness occupies (square ends), shape (4, 2)."""
    a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    length = float(np.hypot(*(b - a)))
    angle = math.atan2(b[1] - a[1], b[0] - a[0])
    return box_corners((a + b) / 2.0, (length, thickness), angle)


def signed_area(points: np.ndarray) -> float:
    """Shoelace area: positive for counter-clockwise outlines."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def segments_cross(p1: np.ndarray, p2: np.ndarray, q1: np.ndarray, q2: np.ndarray) -> bool:
    """True when two segments properly intersect (cross at a point interior to both)."""
    d1, d2 = _cross(q1, q2, p1), _cross(q1, q2, p2)
    d3, d4 = _cross(p1, p2, q1), _cross(p1, p2, q2)
    return d1 * d2 < 0 and d3 * d4 < 0


def is_simple_polygon(points: np.ndarray) -> bool:
    """True when no two non-adjacent edges of the closed outline cross."""
    n = len(points)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # adjacent through the closing edge
            if segments_cross(points[i], points[(i + 1) % n], points[j], points[(j + 1) % n]):
                return False
    return True


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    denom = float(np.dot(ab, ab))
    t = 0.0 if denom == 0.0 else min(1.0, max(0.0, float(np.dot(p - a, ab)) / denom))
    return float(np.hypot(*(p - (a + t * ab))))


def point_in_polygon(p: Point, points: np.ndarray) -> bool:
    """Even-odd rule; works for concave outlines of either winding."""
    x, y = float(p[0]), float(p[1])
    inside = False
    n = len(points)
    for i in range(n):
        (x1, y1), (x2, y2) = points[i], points[(i + 1) % n]
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def distance_to_polygon(p: Point, points: np.ndarray) -> float:
    """Distance from a point to a filled polygon: 0 inside, else to the nearest edge."""
    q = np.asarray(p, dtype=float)
    if point_in_polygon(q, points):
        return 0.0
    n = len(points)
    return min(point_segment_distance(q, points[i], points[(i + 1) % n]) for i in range(n))


def wrap_angle(angle: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def thinness(points: np.ndarray) -> float:
    """A lower bound on a simple polygon's thinnest width: the smallest distance from a vertex to
    an edge not touching it (equal to the minimum width for convex polygons; across a notch of a
    concave one it may underestimate, which only errs on the safe side)."""
    n = len(points)
    best = math.inf
    for i in range(n):
        for j in range(n):
            if j == i or (j + 1) % n == i:
                continue
            best = min(best, point_segment_distance(points[i], points[j], points[(j + 1) % n]))
    return best


def polygons_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """True when two simple polygons (either winding, concave allowed) share interior area:
    an edge of one properly crosses an edge of the other, or one holds a vertex of the other."""
    na, nb = len(a), len(b)
    for i in range(na):
        for j in range(nb):
            if segments_cross(a[i], a[(i + 1) % na], b[j], b[(j + 1) % nb]):
                return True
    # Vertices and edge midpoints of one inside the other (midpoints catch equal outlines).
    mid_a = (a + np.roll(a, -1, axis=0)) / 2.0
    mid_b = (b + np.roll(b, -1, axis=0)) / 2.0
    return (any(point_in_polygon(p, b) and distance_to_outline(p, b) > 1e-9 for p in np.vstack([a, mid_a]))
            or any(point_in_polygon(p, a) and distance_to_outline(p, a) > 1e-9
                   for p in np.vstack([b, mid_b])))


def distance_to_outline(p: Point, points: np.ndarray) -> float:
    """Distance from a point to the nearest edge of a closed outline (inside or out)."""
    q = np.asarray(p, dtype=float)
    n = len(points)
    return min(point_segment_distance(q, points[i], points[(i + 1) % n]) for i in range(n))
