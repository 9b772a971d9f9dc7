"""Plane geometry for scenario validation and maps: shapely 2 (GEOS) does the tests, numpy the
few formulas GEOS has no call for (corners of boxes and walls, a signed area, angle wrapping).

Outlines are (n, 2) arrays [m] of a polygon's corners in order, not closed (the first point is
not repeated), either winding. Functions here build a shapely geometry per call; code that tests
many things against one outline should build it once with :func:`polygon`.
"""
from __future__ import annotations

import math
import re
from typing import Sequence

import numpy as np
import shapely

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
    """Shoelace area [m^2]: positive for counter-clockwise outlines (closed or not). GEOS gives
    only the unsigned area; the sign is the winding, which maps and pymunk need."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def wrap_angle(angle: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def polygon(points: np.ndarray) -> shapely.Polygon:
    """The filled polygon of an outline (n, 2) [m]."""
    return shapely.Polygon(np.asarray(points, dtype=float))


def polygons(outlines: Sequence[np.ndarray]) -> np.ndarray:
    """Filled polygons of many outlines (each (n_i, 2) [m], closed or not), built in one
    vectorised call: an array of shapely polygons."""
    if not len(outlines):
        return np.empty(0, dtype=object)
    arrays = [np.asarray(o, dtype=float) for o in outlines]
    index = np.repeat(np.arange(len(arrays)), [len(a) for a in arrays])
    return np.asarray(shapely.polygons(shapely.linearrings(np.concatenate(arrays),
                                                           indices=index)), dtype=object)


_REASON = re.compile(r"^(?P<what>[^\[]*)\[(?P<x>\S+) (?P<y>\S+)\]$")


def polygon_problem(points: np.ndarray) -> str | None:
    """Why an outline is not a usable simple polygon, naming where, or None when it is one.

    GEOS's validity reason says what is wrong and where ("Self-intersection[1.5 2]"); the
    zero-area and near-pinch tests are ours: GEOS calls a polygon with a repeated neighbour or a
    vertex 1e-12 m off an edge valid, but pymunk cannot stop anything at a pinch of no width.
    """
    pts = np.asarray(points, dtype=float)
    repeats = np.flatnonzero(np.isclose(pts, np.roll(pts, -1, axis=0)).all(axis=1))
    if len(repeats):
        return f"point {repeats[0]} repeats its neighbour"
    shape = polygon(pts)
    if shapely.area(shapely.convex_hull(shape)) < 1e-9:
        return "zero area (the points lie on one line)"
    reason = shapely.is_valid_reason(shape)
    if reason != "Valid Geometry":
        match = _REASON.match(str(reason))
        if match is None:
            return reason
        where = _at(float(match["x"]), float(match["y"]))
        if match["what"] == "Self-intersection":
            return f"edges cross each other {where}"
        if match["what"] == "Ring Self-intersection":
            return (f"the outline touches itself {where} (a point repeats another or lies on "
                    "an edge)")
        return f"{match['what'].strip().lower()} {where}"
    if shapely.area(shape) < 1e-9:
        return "zero area"
    if shapely.minimum_clearance(shape) < 1e-9:  # a pinch has no width: nothing stops at it
        x, y = shapely.get_coordinates(shapely.minimum_clearance_line(shape))[0]
        return (f"the outline touches itself {_at(x, y)} (a point repeats another or lies on "
                "an edge)")
    return None


def _at(x: float, y: float) -> str:
    """'at (x, y)' to the nanometre, for messages (a pinch 1e-12 m wide reads as its place)."""
    return f"at ({round(x, 9) + 0.0:.6g}, {round(y, 9) + 0.0:.6g})"


def thinness(points: np.ndarray) -> float:
    """A lower bound on a simple polygon's thinnest width [m]: GEOS's minimum clearance, the
    smallest distance from a vertex to an edge not touching it.

    Not ``shapely.minimum_width``: that is the width of the convex hull, which misses the thin
    arm of an L (what a wall may skip over). The clearance is exact across a convex polygon's
    short side and errs low elsewhere (about one side of a many-sided disc), on the safe side.
    """
    return float(shapely.minimum_clearance(polygon(points)))


def thinnesses(outlines: Sequence[np.ndarray]) -> np.ndarray:
    """:func:`thinness` of many outlines at once (one vectorised GEOS call) [m]."""
    return np.asarray(shapely.minimum_clearance(polygons(outlines)), dtype=float)


def point_in_polygon(p: Point, points: np.ndarray) -> bool:
    """Whether a point lies inside or on the outline of a polygon (either winding)."""
    return bool(shapely.intersects_xy(polygon(points), float(p[0]), float(p[1])))


def distance_to_polygon(p: Point, points: np.ndarray) -> float:
    """Distance [m] from a point to a filled polygon: 0 inside, else to the nearest edge."""
    return float(shapely.distance(polygon(points), shapely.Point(float(p[0]), float(p[1]))))


def polygons_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """True when two simple polygons (either winding, concave allowed) share interior area;
    touching along an edge or at a corner is not an overlap."""
    return bool(shapely.relate_pattern(polygon(a), polygon(b), "T********"))
