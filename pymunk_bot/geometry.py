"""Plain 2D geometry on numpy arrays (no pymunk): used to validate scenarios and build maps."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

Point = Sequence[float] | np.ndarray  # (x, y): a tuple, list or array


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
    """True when no two non-adjacent edges of the closed outline cross.

    Vectorised over edge pairs in blocks of rows, so 2,000 points take well under a second.
    """
    pts = np.asarray(points, dtype=float)
    n = len(pts)
    a, b = pts, np.roll(pts, -1, axis=0)  # edge k runs from a[k] to b[k]
    j = np.arange(n)
    for start in range(0, n, _BLOCK):
        i = np.arange(start, min(n, start + _BLOCK))[:, None]
        p1, p2 = a[i[:, 0]][:, None, :], b[i[:, 0]][:, None, :]
        d1, d2 = _cross_v(a, b, p1), _cross_v(a, b, p2)
        d3, d4 = _cross_v(p1, p2, a[None]), _cross_v(p1, p2, b[None])
        crossing = (d1 * d2 < 0) & (d3 * d4 < 0)
        pairs = (j[None, :] >= i + 2) & ~((i == 0) & (j[None, :] == n - 1))
        if np.any(crossing & pairs):
            return False
    return True


_BLOCK = 256  # rows of edge pairs tested at once (256 x n doubles per array)


def _cross_v(o: np.ndarray, a: np.ndarray, p: np.ndarray) -> np.ndarray:
    """z of (a - o) x (p - o), broadcast over leading axes."""
    return (a[..., 0] - o[..., 0]) * (p[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (
        p[..., 0] - o[..., 0])


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    denom = float(np.dot(ab, ab))
    t = 0.0 if denom == 0.0 else min(1.0, max(0.0, float(np.dot(p - a, ab)) / denom))
    return float(np.hypot(*(p - (a + t * ab))))


def point_in_polygon(p: Point, points: np.ndarray) -> bool:
    """Even-odd rule; works for concave outlines of either winding."""
    x, y = float(p[0]), float(p[1])
    pts = np.asarray(points, dtype=float)
    x1, y1 = pts[:, 0], pts[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    spans = (y1 > y) != (y2 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
    return bool(np.count_nonzero(spans & (x < x_at)) % 2)


def _segment_distances(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points ``p`` to segments a-b, broadcast over leading axes."""
    ab = b - a
    denom = (ab * ab).sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(denom > 0, ((p - a) * ab).sum(axis=-1) / denom, 0.0)
    t = np.clip(t, 0.0, 1.0)
    return np.hypot(*np.moveaxis(p - (a + t[..., None] * ab), -1, 0))


def distance_to_polygon(p: Point, points: np.ndarray) -> float:
    """Distance from a point to a filled polygon: 0 inside, else to the nearest edge."""
    q = np.asarray(p, dtype=float)
    pts = np.asarray(points, dtype=float)
    if point_in_polygon(q, pts):
        return 0.0
    return float(_segment_distances(q, pts, np.roll(pts, -1, axis=0)).min())


def wrap_angle(angle: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def thinness(points: np.ndarray) -> float:
    """A lower bound on a simple polygon's thinnest width: the smallest distance from a vertex to
    an edge not touching it (equal to the minimum width for convex polygons; across a notch of a
    concave one it may underestimate, which only errs on the safe side)."""
    pts = np.asarray(points, dtype=float)
    n = len(pts)
    a, b = pts, np.roll(pts, -1, axis=0)  # edge j runs from vertex j to vertex j + 1
    j = np.arange(n)
    best = math.inf
    for start in range(0, n, _BLOCK):
        i = np.arange(start, min(n, start + _BLOCK))[:, None]
        d = _segment_distances(pts[i[:, 0]][:, None, :], a[None], b[None])
        touching = (j[None, :] == i) | ((j[None, :] + 1) % n == i)
        d = np.where(touching, np.inf, d)
        best = min(best, float(d.min()))
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
