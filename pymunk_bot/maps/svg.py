"""SVG floor plans (parsed by svgelements) as static map geometry in world metres.

The map is what a browser paints:
- Every shape with a fill (SVG's default fill is black; ``fill="none"`` or a transparent fill
  paints nothing) is a solid obstacle over the area it fills: rect, circle, ellipse, polygon,
  polyline and path (an open polyline or path fills the area its closing line encloses).
- Every shape with a stroke is also a wall along its outline as wide as the stroke (pymunk
  segments with round caps): this is how a line or an unfilled polyline becomes a wall.
- Transforms (on shapes and groups) and the viewBox are applied; ``display="none"`` shapes are
  skipped. Curves (arcs, Bezier curves, circles, ellipses) are sampled so that no chord is more
  than 1 cm from the curve.
- Coordinates are SVG user units (viewBox units) times ``map_scale`` metres. SVG's y axis points
  down, so it is flipped; the bottom-left corner of the plan (its viewBox, else its width and
  height, else the drawing's bounding box) is the world origin, and the plan's edge is a wall.

A filled outline that neither contains nor lies inside another outline of the same shape
becomes convex pieces; nested outlines (a wall ring with a room inside) become chains of
segments, so a hole is never filled.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import shapely

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.geometry.plane import signed_area
from pymunk_bot.maps.outlines import FilledArea, MapGeometry, convex_pieces, edge_chain

CURVE_TOLERANCE = 0.01  # [m] largest distance between a sampled curve and its chords
# Bounds on the work one plan may cost (measured: about 0.3 ms per painted shape to read and
# cut into pieces, 2 s per MB for svgelements to parse; every segment also costs run time).
MAX_FILE_BYTES = 10 << 20  # [bytes] of the SVG file
MAX_SHAPES = 20_000  # painted shapes
MAX_POINTS = 200_000  # sampled outline points in one plan
MAX_CURVE_SAMPLES = 1 << 16  # per curve segment
MAX_REACH = 1e4  # [m] how far a shape may reach beyond the plan (as a map's extent, 10 km)
DEFAULT_MAP_SCALE = 0.01  # [m per user unit]: 1 unit = 1 cm


def read_svg_map(path: str | Path, map_scale: float | None = None, source: str | None = None,
                 key_path: str = "world.map") -> MapGeometry:
    """Read an SVG floor plan into map geometry; ``map_scale`` is metres per SVG user unit
    (default 0.01). Errors name ``source`` and ``key_path`` (the scenario), else the SVG."""
    svg_path = Path(path)

    def fail(problem: str, key: str = "") -> ScenarioError:
        if source is None:
            return ScenarioError(str(svg_path), key, problem)
        return ScenarioError(source, key or key_path, f"{svg_path}: {problem}" if not key
                             else problem)

    scale = DEFAULT_MAP_SCALE if map_scale is None else map_scale
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) \
            or not math.isfinite(scale) or scale <= 0:
        raise fail(f"must be a number > 0 (got {map_scale!r})", "world.map_scale")
    try:
        import svgelements as se
    except ImportError:
        raise fail("reading SVG maps needs svgelements: pip install 'pymunk-bot[maps]'") from None
    if not svg_path.is_file():
        raise fail("map file not found" if not svg_path.exists() else "not a file")
    if svg_path.stat().st_size > MAX_FILE_BYTES:
        raise fail(f"the SVG is {svg_path.stat().st_size / 2**20:.1f} MB; a plan may have at "
                   f"most {MAX_FILE_BYTES >> 20} MB")
    try:
        svg = se.SVG.parse(str(svg_path), reify=True)
    except Exception as exc:  # svgelements raises ElementTree, ValueError, ... on bad files
        raise fail(f"cannot read the SVG: {type(exc).__name__}: {exc}") from None
    to_user = np.eye(3)
    if svg.viewbox is not None:
        box = [svg.viewbox.x, svg.viewbox.y, svg.viewbox.width, svg.viewbox.height]
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in box):
            raw = str(svg.values.get("viewBox", ""))[:80]
            raise fail(f"the viewBox must be four finite numbers: x y width height (got {raw!r})")
        if not (box[2] > 0 and box[3] > 0):
            raise fail(f"the viewBox has no area ({box[2]:g} x {box[3]:g} user units); its "
                       "width and height must be > 0")
    if svg.viewbox is not None and svg.viewbox_transform:
        to_user = np.linalg.inv(_matrix(se.Matrix(svg.viewbox_transform)))
    px_to_user = math.sqrt(abs(np.linalg.det(to_user[:2, :2])))  # user units per pixel
    tolerance_px = CURVE_TOLERANCE / (scale * px_to_user)
    shapes = _read_shapes(svg, se, to_user, tolerance_px, fail)
    if not shapes:
        raise fail("the SVG has nothing to build a map from: no filled or stroked shapes")
    canvas = _canvas(svg, shapes)
    return _geometry(shapes, canvas, scale, fail)


def _matrix(m) -> np.ndarray:
    return np.array([[m.a, m.c, m.e], [m.b, m.d, m.f], [0.0, 0.0, 1.0]])


def _read_shapes(svg, se, to_user: np.ndarray, tolerance_px: float, fail) -> list[dict]:
    """Each painted shape: its subpaths in user units, whether filled, stroke width [units]."""
    shapes: list[dict] = []
    total = 0
    unit = math.sqrt(abs(np.linalg.det(to_user[:2, :2])))
    for element in svg.elements():
        if not isinstance(element, se.Shape) or element.values.get("visibility") in (
                "hidden", "collapse"):
            continue
        filled = _painted(element.fill) and not isinstance(element, se.SimpleLine)
        stroke = float(element.implicit_stroke_width or 0.0) * unit if _painted(element.stroke) else 0.0
        if not filled and stroke <= 0:
            continue
        if len(shapes) >= MAX_SHAPES:
            raise fail(f"the SVG has more than {MAX_SHAPES:,} painted shapes (each costs time "
                       "to build and to simulate); merge or drop the small ones")
        subpaths = []
        for sub in abs(se.Path(element)).as_subpaths():  # abs(): transform applied
            points, closed = _sample(se.Path(sub), se, tolerance_px)
            if len(points) < 2:
                continue
            total += len(points)
            if total > MAX_POINTS:
                raise fail(f"the SVG's outlines have more than {MAX_POINTS:,} points")
            user = points @ to_user[:2, :2].T + to_user[:2, 2]
            subpaths.append((user, closed))
        if subpaths:
            rule = str(element.values.get("fill-rule", "nonzero")).strip()
            shapes.append({"subpaths": subpaths, "filled": filled, "stroke": stroke,
                           "nonzero": rule != "evenodd"})
    return shapes


def _painted(color) -> bool:
    return color is not None and color.value is not None and color.alpha > 0


def _sample(path, se, tolerance: float) -> tuple[np.ndarray, bool]:
    """Points along one subpath (pixels) and whether it ends with a close."""
    points: list[np.ndarray] = []
    closed = False
    for segment in path:
        if isinstance(segment, se.Move):
            points.append(np.array([[segment.end.x, segment.end.y]]))
        elif isinstance(segment, (se.Line, se.Close)):
            closed = closed or isinstance(segment, se.Close)
            if segment.end is not None:
                points.append(np.array([[segment.end.x, segment.end.y]]))
        elif segment.end is not None:  # a curve: Arc, QuadraticBezier, CubicBezier
            points.append(_sample_curve(segment, tolerance)[1:])
    if not points:
        return np.empty((0, 2)), False
    out = np.concatenate(points)
    keep = np.ones(len(out), dtype=bool)
    keep[1:] = np.any(out[1:] != out[:-1], axis=1)  # drop repeated points
    out = out[keep]
    if len(out) > 2 and np.allclose(out[0], out[-1]):
        out, closed = out[:-1], True
    return out, closed


def _sample_curve(segment, tolerance: float) -> np.ndarray:
    """Samples of a curve, doubled until every chord's midpoint is within ``tolerance`` of the
    curve at the middle parameter (and the chord ends are on it)."""
    n = 8
    while True:
        t = np.linspace(0.0, 1.0, n + 1)
        points = np.asarray(segment.npoint(t), dtype=float)
        middle = np.asarray(segment.npoint((t[:-1] + t[1:]) / 2), dtype=float)
        chord_mid = (points[:-1] + points[1:]) / 2
        if n >= MAX_CURVE_SAMPLES or np.hypot(*(middle - chord_mid).T).max() <= tolerance / 2:
            return points
        n *= 2


def _canvas(svg, shapes: list[dict]) -> tuple[float, float, float, float]:
    """(x, y, width, height) of the plan in user units."""
    if svg.viewbox is not None:
        vb = svg.viewbox
        return (float(vb.x), float(vb.y), float(vb.width), float(vb.height))
    if "width" in svg.values and "height" in svg.values and svg.width > 0 and svg.height > 0:
        return (0.0, 0.0, float(svg.width), float(svg.height))
    points = np.concatenate([p for s in shapes for p, _ in s["subpaths"]])
    pad = max(s["stroke"] for s in shapes) / 2
    lo, hi = points.min(axis=0) - pad, points.max(axis=0) + pad
    return (float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1]))


def _geometry(shapes: list[dict], canvas, scale: float, fail) -> MapGeometry:
    cx, cy, cw, ch = canvas
    if not (cw > 0 and ch > 0):
        raise fail(f"the plan has no area ({cw:g} x {ch:g} user units)")
    reach = MAX_REACH / scale  # [user units]
    for k, shape in enumerate(shapes):
        points = np.concatenate([p for p, _ in shape["subpaths"]])
        lo, hi = points.min(axis=0), points.max(axis=0)
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()) or lo[0] < cx - reach \
                or lo[1] < cy - reach or hi[0] > cx + cw + reach or hi[1] > cy + ch + reach:
            raise fail(f"painted shape {k + 1} reaches from ({lo[0]:.6g}, {lo[1]:.6g}) to "
                       f"({hi[0]:.6g}, {hi[1]:.6g}) user units, more than {MAX_REACH:g} m beyond "
                       "the plan")

    def to_world(user: np.ndarray) -> np.ndarray:
        return np.stack([(user[:, 0] - cx) * scale, (cy + ch - user[:, 1]) * scale], axis=1)

    polygons: list[np.ndarray] = []
    segments: list[np.ndarray] = []
    radii: list[np.ndarray] = []
    filled: list[FilledArea] = []
    for shape in shapes:
        world = [(to_world(p), closed) for p, closed in shape["subpaths"]]
        if shape["stroke"] > 0:
            for points, closed in world:
                chain = edge_chain(np.vstack([points, points[:1]]) if closed else points)
                segments.append(chain)
                radii.append(np.full(len(chain), shape["stroke"] * scale / 2))
        if shape["filled"]:
            outlines = [p for p, _ in world if len(p) >= 3]
            if outlines:
                filled.append(FilledArea(tuple(outlines), shape["nonzero"]))
            for i, outline in enumerate(outlines):
                nested = any(_inside(o, outline) or _inside(outline, o)
                             for j, o in enumerate(outlines) if j != i)
                ring = np.vstack([outline, outline[:1]])
                area = signed_area(outline)
                pieces = None if nested or area == 0 else convex_pieces(ring if area > 0
                                                                        else ring[::-1])
                if pieces is None:
                    segments.append(edge_chain(ring))
                    radii.append(np.zeros(len(ring) - 1))
                else:
                    polygons += pieces
    width, height = cw * scale, ch * scale
    border = np.array([[0.0, 0.0], [width, 0.0], [width, height], [0.0, height], [0.0, 0.0]])
    segments.append(edge_chain(border))  # the plan's edge is a wall
    radii.append(np.zeros(4))
    return MapGeometry(tuple(polygons), np.concatenate(segments), np.concatenate(radii),
                       (0.0, 0.0, width, height), filled=tuple(filled))


def _inside(inner: np.ndarray, outer: np.ndarray) -> bool:
    """Whether outline ``inner`` lies inside ``outer`` (tested with its first point)."""
    lo, hi = outer.min(axis=0), outer.max(axis=0)
    if (inner.min(axis=0) < lo).any() or (inner.max(axis=0) > hi).any():
        return False
    return bool(shapely.contains_xy(shapely.Polygon(outer), inner[0, 0], inner[0, 1]))
