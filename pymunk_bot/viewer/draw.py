"""Draw a Scene onto a pygame surface: arena, obstacles, trails, paths, goals, LiDAR, robots."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pygame

from pymunk_bot.geometry.footprint import transform
from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer import primitives as prim
from pymunk_bot.viewer.camera import Camera
from pymunk_bot.viewer.draw_localization import draw_built_map, draw_localization
from pymunk_bot.viewer.scene import RobotView, Scene, ShapeView

GRID_SPACINGS = (0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)  # [m]
MAJOR_SPACINGS = (0.5, 1.0, 5.0, 10.0, 50.0, 100.0, 500.0)  # [m] darker lines
MIN_GRID_PX = 28  # grid lines closer than this would be clutter
RAY_LINE_BUDGET = 1000  # beams drawn as lines at most, over all robots (hit points: always)
AA_RAYS = 90  # a robot's rays are antialiased up to this many beams


@dataclass
class Layers:
    """Which optional layers are drawn (the window toggles them with keys)."""

    rays: bool = True
    trails: bool = True
    grid: bool = True
    ghost: bool = True  # odometry estimate
    paths: bool = True
    labels: bool = True
    built_map: bool = True  # the occupancy grid a robot is building (mapping / slam)
    particles: bool = True  # the localizer's particle cloud
    covariance: bool = True  # the estimate's 95 % ellipse
    estimate: bool = True  # the localizer's pose, beside the true one


class StaticLayer:
    """The part of a frame that does not move (background, floor, grid, fixed obstacles), drawn
    once per view and blitted: most of a frame's drawing time in a walled arena."""

    def __init__(self) -> None:
        self._key: tuple | None = None
        self._surface: pygame.Surface | None = None

    def blit(self, surface: pygame.Surface, scene: Scene, camera: Camera, grid: bool) -> None:
        fixed = [s for s in scene.shapes if not s.movable]
        key = (surface.get_size(), camera.scale, tuple(camera.centre), grid, scene.width,
               scene.height, tuple(scene.origin), tuple(id(s) for s in fixed))
        if key != self._key or self._surface is None:
            self._surface = pygame.Surface(surface.get_size())
            _draw_static(self._surface, scene, camera, grid, fixed)
            self._key = key
        surface.blit(self._surface, (0, 0))


def _draw_static(surface: pygame.Surface, scene: Scene, camera: Camera, grid: bool,
                 fixed: list[ShapeView]) -> None:
    surface.fill(pal.BACKGROUND)
    ox, oy = scene.origin
    floor = camera.points_to_screen(np.array([[ox, oy], [ox + scene.width, oy + scene.height]]))
    (x0, y1), (x1, y0) = floor
    pygame.draw.rect(surface, pal.FLOOR, pygame.Rect(round(x0), round(y0),
                                                     round(x1 - x0), round(y1 - y0)))
    if grid:
        _grid(surface, camera, (ox, oy, ox + scene.width, oy + scene.height))
    _shapes(surface, camera, fixed)


def draw_scene(surface: pygame.Surface, scene: Scene, camera: Camera, layers: Layers,
               selected: str | None = None, font: pygame.font.Font | None = None,
               halo: bool = True, static: StaticLayer | None = None) -> None:
    """Render ``scene`` as seen through ``camera``. Reads the scene only.

    ``selected`` names the robot whose rays are drawn when there are too many to draw them
    all; ``halo`` rings it (the window does, recordings do not). ``static`` caches what does
    not move between frames.
    """
    if static is not None:
        static.blit(surface, scene, camera, layers.grid)
    else:
        _draw_static(surface, scene, camera, layers.grid,
                     [s for s in scene.shapes if not s.movable])
    robots = scene.robots
    if layers.built_map:  # what the robots' mapping has built so far, over the fixed scene
        for r in robots:
            draw_built_map(surface, camera, r)
    _shapes(surface, camera, [s for s in scene.shapes if s.movable])
    if layers.rays:
        # Beyond a budget, lines for the selected robot only: thousands of rays hide the scene
        # and take longer to draw than the physics takes to run.
        beams = sum(len(r.scan_points) for r in robots if r.scan_points is not None)
        for r in robots:
            _rays(surface, camera, r, lines=beams <= RAY_LINE_BUDGET or r.name == selected)
    if layers.trails:
        for r in robots:
            if len(r.trail) > 1:
                prim.polyline(surface, pal.mix(pal.robot_colour(r.index), pal.FLOOR, 0.3),
                              camera.points_to_screen(r.trail), width=2)
    for r in robots:
        _goal(surface, camera, r, font)
        if layers.paths and r.path is not None and len(r.path) > 1:
            prim.dashed_polyline(surface, pal.robot_colour(r.index),
                                 camera.points_to_screen(r.path))
    if layers.ghost:
        for r in robots:
            _ghost(surface, camera, r)
    for r in robots:
        draw_localization(surface, camera, r, layers)
    for r in robots:
        _robot(surface, camera, r, halo and r.name == selected)
    if layers.labels and font is not None and len(robots) > 1:
        for r in robots:
            _label(surface, camera, r, font)


def _grid(surface: pygame.Surface, camera: Camera,
          extent: tuple[float, float, float, float]) -> None:
    x0, y0, x1, y1 = extent
    spacing = next((s for s in GRID_SPACINGS if s * camera.scale >= MIN_GRID_PX),
                   GRID_SPACINGS[-1])
    major = next((m for m in MAJOR_SPACINGS if m >= 2 * spacing), MAJOR_SPACINGS[-1])
    every = int(round(major / spacing))
    (left, top), (right, bottom) = camera.points_to_screen(np.array([[x0, y1], [x1, y0]]))
    sw, sh = surface.get_size()
    # Only lines that can be seen: the arena cut to the visible window.
    wx0, wy1 = camera.to_world(0, 0)
    wx1, wy0 = camera.to_world(sw, sh)
    top_c, bottom_c = max(top, 0), min(bottom, sh)
    left_c, right_c = max(left, 0), min(right, sw)
    for k in range(math.ceil(max(wx0, x0) / spacing), math.floor(min(wx1, x1) / spacing) + 1):
        x = round(camera.to_screen(k * spacing, 0)[0])
        colour = pal.GRID_MAJOR if k % every == 0 else pal.GRID
        pygame.draw.line(surface, colour, (x, top_c), (x, bottom_c))
    for k in range(math.ceil(max(wy0, y0) / spacing), math.floor(min(wy1, y1) / spacing) + 1):
        y = round(camera.to_screen(0, k * spacing)[1])
        colour = pal.GRID_MAJOR if k % every == 0 else pal.GRID
        pygame.draw.line(surface, colour, (left_c, y), (right_c, y))


def _colours(shape: ShapeView):
    if shape.wall:
        return pal.WALL, pal.WALL
    if shape.movable:
        return pal.MOVABLE, pal.MOVABLE_EDGE
    return pal.STATIC, pal.STATIC_EDGE


def _shapes(surface: pygame.Surface, camera: Camera, shapes: list[ShapeView]) -> None:
    """Obstacles; a concave one (several convex pieces) gets one outline, not one per piece."""
    pieces: dict[int, list[np.ndarray]] = {}
    for shape in shapes:
        fill, edge = _colours(shape)
        pts = camera.points_to_screen(shape.points)
        if shape.kind == "circle":
            prim.circle(surface, fill, edge, tuple(pts[0]), camera.length(shape.radius))
        elif shape.kind == "segment":
            prim.line(surface, fill, tuple(pts[0]), tuple(pts[1]),
                      max(1.0, 2 * camera.length(shape.radius)))
        elif shape.group >= 0:
            prim.polygon(surface, fill, fill, pts)
            pieces.setdefault(shape.group, []).append(shape.points)
        else:
            prim.polygon(surface, fill, edge, pts)
    by_group = {s.group: s for s in shapes if s.group >= 0}
    for group, polys in pieces.items():
        _, edge = _colours(by_group[group])
        for a, b in _outer_edges(polys):
            pygame.draw.aaline(surface, edge, camera.to_screen(*a), camera.to_screen(*b))
    for group, polys in pieces.items():
        if by_group[group].movable:
            _crate_mark(surface, camera.points_to_screen(np.concatenate(polys)), None)
    for shape in shapes:
        if shape.movable and shape.kind == "circle":
            _crate_mark(surface, camera.points_to_screen(shape.points),
                        camera.length(shape.radius))


def _outer_edges(polys: list[np.ndarray]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Edges of the pieces that no other piece shares: the outline of their union."""
    def key(p: np.ndarray) -> tuple[float, float]:
        return (round(float(p[0]), 9), round(float(p[1]), 9))

    edges = []
    count: dict[frozenset, int] = {}
    for poly in polys:
        for i in range(len(poly)):
            a, b = poly[i], poly[(i + 1) % len(poly)]
            k = frozenset((key(a), key(b)))
            count[k] = count.get(k, 0) + 1
            edges.append((k, a, b))
    return [(a, b) for k, a, b in edges if count[k] == 1]


def _crate_mark(surface: pygame.Surface, pts: np.ndarray, radius_px: float | None) -> None:
    """An 'x' across a movable obstacle, so it differs from fixed ones by more than its hue."""
    if radius_px is not None:
        c, half = pts[0], 0.5 * radius_px
    else:
        c = pts.mean(axis=0)
        span = pts.max(axis=0) - pts.min(axis=0)
        half = 0.3 * float(min(span))
    if half < 2:
        return
    for sx in (-1, 1):
        prim.line(surface, pal.MOVABLE_EDGE, (c[0] - half, c[1] - sx * half),
                  (c[0] + half, c[1] + sx * half), 2)


def _rays(surface: pygame.Surface, camera: Camera, r: RobotView, lines: bool = True) -> None:
    if r.scan_points is None or r.scan_origin is None or len(r.scan_points) == 0:
        return
    colour = pal.robot_colour(r.index)
    ends = camera.points_to_screen(r.scan_points)
    if lines:
        ray_colour = pal.mix(colour, pal.FLOOR, 0.78)
        origin = camera.to_screen(*r.scan_origin)
        # Antialiased lines cost 20x plain ones (30 ms for 360 long rays at 1280 px): smooth
        # only a few rays; a fan of many is a faint texture where jaggies do not show.
        draw = pygame.draw.aaline if len(ends) <= AA_RAYS else pygame.draw.line
        for x, y in ends:
            draw(surface, ray_colour, origin, (x, y))
    size = 2 if camera.scale < 120 else 3
    sprite = _dot(pal.mix(colour, (0, 0, 0), 0.25), size)
    w, h = surface.get_size()
    hits = ends[r.scan_hit]
    visible = (hits[:, 0] > -size) & (hits[:, 0] < w + size) & (hits[:, 1] > -size) & (
        hits[:, 1] < h + size)
    corners = np.rint(hits[visible] - size - 1).astype(int).tolist()
    surface.blits([(sprite, (x, y)) for x, y in corners], doreturn=False)


_DOTS: dict[tuple, pygame.Surface] = {}


def _dot(colour, radius: int) -> pygame.Surface:
    """A small antialiased disc, drawn once and blitted for every LiDAR hit."""
    key = (colour, radius)
    if key not in _DOTS:
        sprite = pygame.Surface((2 * radius + 3, 2 * radius + 3), pygame.SRCALPHA)
        prim.circle(sprite, colour, colour, (radius + 1, radius + 1), radius)
        _DOTS[key] = sprite
    return _DOTS[key]


def _goal(surface: pygame.Surface, camera: Camera, r: RobotView,
          font: pygame.font.Font | None = None) -> None:
    """The task goal: a solid ring of the goal tolerance with a +, filled once reached. A goal
    the controller drives to instead (a click, or its own block's goal): a dashed ring with an
    x. With both on screen, each is labelled, so the one that judges the run is never mistaken
    for the other."""
    colour = pal.robot_colour(r.index)
    both = r.goal is not None and r.nav_goal is not None
    if r.goal is not None:
        cx, cy = camera.to_screen(*r.goal)
        tol = max(camera.length(r.goal_tolerance), 4.0)
        fill = pal.mix(colour, pal.FLOOR, 0.82) if r.goal_reached else None
        prim.circle(surface, fill, colour, (cx, cy), tol)
        arm = max(6.0, 0.6 * tol)
        prim.line(surface, colour, (cx - arm, cy), (cx + arm, cy), 2)
        prim.line(surface, colour, (cx, cy - arm), (cx, cy + arm), 2)
        if both and font is not None:
            _goal_label(surface, font, f"{r.name} task goal", (cx, cy), tol)
    if r.nav_goal is not None:
        cx, cy = camera.to_screen(*r.nav_goal)
        tol = max(camera.length(r.goal_tolerance), 4.0)
        prim.dashed_ring(surface, colour, (cx, cy), tol)
        arm = max(5.0, 0.45 * tol)
        prim.line(surface, colour, (cx - arm, cy - arm), (cx + arm, cy + arm), 2)
        prim.line(surface, colour, (cx - arm, cy + arm), (cx + arm, cy - arm), 2)
        if both and font is not None:
            _goal_label(surface, font, f"{r.name} drive-to goal", (cx, cy), tol)


def _goal_label(surface: pygame.Surface, font: pygame.font.Font, text: str,
                centre: tuple[float, float], radius: float) -> None:
    rendered = font.render(text, True, pal.OUTLINE)  # above right: the robot may sit on it
    surface.blit(rendered, (centre[0] + 0.7 * radius + 2, centre[1] - 0.7 * radius - 2
                            - rendered.get_height()))


def _ghost(surface: pygame.Surface, camera: Camera, r: RobotView) -> None:
    """The odometry estimate: a dashed outline with a heading tick."""
    colour = pal.mix(pal.robot_colour(r.index), pal.FLOOR, 0.35)
    x, y, theta = (float(v) for v in r.odometry)
    centre = camera.to_screen(x, y)
    radius = max(camera.length(r.radius), 3.0)
    prim.dashed_ring(surface, colour, centre, radius)
    tip = camera.to_screen(x + r.radius * math.cos(theta), y + r.radius * math.sin(theta))
    prim.line(surface, colour, centre, tip, 1)


def _robot(surface: pygame.Surface, camera: Camera, r: RobotView, selected: bool) -> None:
    x, y, theta = (float(v) for v in r.pose)
    centre = camera.to_screen(x, y)
    radius = max(camera.length(r.radius), 3.0)
    if selected:
        prim.ring(surface, pal.SELECTION, centre, radius + 3, 3)
    if r.footprint is None:
        prim.circle(surface, pal.robot_colour(r.index), pal.OUTLINE, centre, radius)
        tip = (centre[0] + radius * math.cos(theta), centre[1] - radius * math.sin(theta))
        prim.line(surface, pal.HEADING, centre, tip, max(2.0, radius / 6))
        return
    outline = transform(r.footprint, r.pose)
    prim.polygon(surface, pal.robot_colour(r.index), pal.OUTLINE, camera.points_to_screen(outline))
    reach = float(np.max(r.footprint[:, 0]))  # heading line from the pose point to the nose
    tip = camera.to_screen(x + reach * math.cos(theta), y + reach * math.sin(theta))
    prim.line(surface, pal.HEADING, centre, tip, max(2.0, radius / 8))
    prim.circle(surface, pal.HEADING, pal.HEADING, centre, max(2.0, radius / 10))
    if r.steering is not None and r.wheelbase > 0:
        _front_wheels(surface, camera, r, r.steering, r.footprint)


def _front_wheels(surface: pygame.Surface, camera: Camera, r: RobotView, steering: float,
                  footprint: np.ndarray) -> None:
    """A car's front wheels at the front axle, turned by the steering angle."""
    x, y, theta = (float(v) for v in r.pose)
    half_width = 0.5 * float(np.ptp(footprint[:, 1])) * 0.8
    half_tyre = 0.12 * r.wheelbase + 0.01  # [m]
    c, s = math.cos(theta), math.sin(theta)
    heading = theta + steering
    dc, ds = math.cos(heading) * half_tyre, math.sin(heading) * half_tyre
    for side in (-1.0, 1.0):
        wx = x + c * r.wheelbase - s * side * half_width
        wy = y + s * r.wheelbase + c * side * half_width
        prim.line(surface, pal.OUTLINE, camera.to_screen(wx - dc, wy - ds),
                  camera.to_screen(wx + dc, wy + ds), max(2.0, camera.length(0.03)))


def _label(surface: pygame.Surface, camera: Camera, r: RobotView, font: pygame.font.Font) -> None:
    x, y, _ = (float(v) for v in r.pose)
    cx, cy = camera.to_screen(x, y)
    text = font.render(r.name, True, pal.OUTLINE)
    radius = max(camera.length(r.radius), 3.0)
    surface.blit(text, (cx - text.get_width() / 2, cy + radius + 4))
