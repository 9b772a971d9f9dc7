"""Draw what a robot believes: the map it is building, its particle cloud, its estimate and the
estimate's 95 % covariance ellipse (layers ``built_map``, ``particles``, ``estimate``,
``covariance``; keys m, k, e, v)."""
from __future__ import annotations

import math

import numpy as np
import pygame

from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer import primitives as prim
from pymunk_bot.viewer.camera import Camera
from pymunk_bot.viewer.scene import RobotView

CHI2_2D_95 = 5.991  # chi^2(2) at 95 %: the position ellipse holds the truth 95 % of the time
Z_95 = 1.96  # two-sided normal quantile: the heading fan
ELLIPSE_POINTS = 64
HEADING_TICKS_MAX = 2000  # particles drawn with a heading tick at most (beyond: dots only)
MAP_OCCUPIED_ALPHA = 210  # [0..255] a surely occupied cell
MAP_FREE_ALPHA = 45  # [0..255] the tint of a cell seen free


def draw_built_map(surface: pygame.Surface, camera: Camera, r: RobotView) -> None:
    """The robot's occupancy grid under everything: unknown transparent, free tinted in the
    robot's colour, occupied dark by its probability."""
    grid = r.built_map
    if grid is None:
        return
    data = np.asarray(grid.data)
    res = float(grid.resolution)
    ox, oy = (float(v) for v in grid.origin)
    # Only the cells on screen (a deep zoom would otherwise scale the whole grid up).
    sw, sh = surface.get_size()
    wx0, wy1 = camera.to_world(0, 0)
    wx1, wy0 = camera.to_world(sw, sh)
    c0, c1 = max(0, math.floor((wx0 - ox) / res)), min(grid.cols, math.ceil((wx1 - ox) / res))
    r0, r1 = max(0, math.floor((wy0 - oy) / res)), min(grid.rows, math.ceil((wy1 - oy) / res))
    if c0 >= c1 or r0 >= r1:
        return
    cells = data[r0:r1, c0:c1][::-1]  # screen rows go down, grid rows go up
    rgba = np.zeros(cells.shape + (4,), dtype=np.uint8)
    known = cells >= 0
    p = np.clip(cells, 0, 100) / 100.0
    occupied = known & (p >= 0.5)
    free = known & ~occupied
    rgba[free, :3] = pal.robot_colour(r.index)
    rgba[free, 3] = MAP_FREE_ALPHA
    shade = (pal.STATIC_EDGE[0] * np.ones_like(p)).astype(np.uint8)
    rgba[occupied, :3] = shade[occupied, None]
    rgba[occupied, 3] = (MAP_OCCUPIED_ALPHA * (2.0 * p[occupied] - 1.0) ** 0.5).astype(np.uint8)
    image = pygame.image.frombuffer(np.ascontiguousarray(rgba).tobytes(),
                                    (cells.shape[1], cells.shape[0]), "RGBA")
    (left, top), (right, bottom) = camera.points_to_screen(
        np.array([[ox + c0 * res, oy + r1 * res], [ox + c1 * res, oy + r0 * res]]))
    size = (max(1, round(right - left)), max(1, round(bottom - top)))
    surface.blit(pygame.transform.scale(image, size), (round(left), round(top)))


def draw_localization(surface: pygame.Surface, camera: Camera, r: RobotView, layers) -> None:
    """Particles, the covariance ellipse and the estimated pose of one robot."""
    colour = pal.robot_colour(r.index)
    if layers.particles and r.particles is not None and len(r.particles):
        _particles(surface, camera, np.asarray(r.particles, dtype=float),
                   pal.mix(colour, (0, 0, 0), 0.35))
    if r.estimate is None:
        return
    x, y, theta = (float(v) for v in r.estimate)
    if layers.covariance and r.covariance is not None:
        _ellipse(surface, camera, np.asarray(r.covariance, dtype=float), (x, y, theta), colour)
    if layers.estimate:
        centre = camera.to_screen(x, y)
        radius = max(camera.length(r.radius), 3.0)
        truth = camera.to_screen(float(r.pose[0]), float(r.pose[1]))
        prim.line(surface, pal.mix(colour, pal.FLOOR, 0.3), centre, truth, 1)  # the error
        prim.ring(surface, pal.mix(colour, (0, 0, 0), 0.2), centre, radius, 2)
        tip = (centre[0] + 1.4 * radius * math.cos(theta), centre[1] - 1.4 * radius * math.sin(theta))
        prim.line(surface, pal.mix(colour, (0, 0, 0), 0.2), centre, tip, 2)


def _particles(surface: pygame.Surface, camera: Camera, particles: np.ndarray, colour) -> None:
    pts = camera.points_to_screen(particles[:, :2])
    w, h = surface.get_size()
    seen = (pts[:, 0] > -8) & (pts[:, 0] < w + 8) & (pts[:, 1] > -8) & (pts[:, 1] < h + 8)
    pts, theta = pts[seen], particles[seen, 2]
    if len(pts) <= HEADING_TICKS_MAX:
        tick = 7.0  # [px]
        ends = pts + tick * np.column_stack([np.cos(theta), -np.sin(theta)])
        for (ax, ay), (bx, by) in zip(pts.tolist(), ends.tolist()):
            pygame.draw.line(surface, colour, (ax, ay), (bx, by))
    dot = pygame.Surface((3, 3))
    dot.fill(colour)
    corners = np.rint(pts - 1).astype(int).tolist()
    surface.blits([(dot, (cx, cy)) for cx, cy in corners], doreturn=False)


def _ellipse(surface: pygame.Surface, camera: Camera, cov: np.ndarray,
             pose: tuple[float, float, float], colour) -> None:
    """The 95 % position ellipse and the 95 % heading fan of a pose covariance."""
    x, y, theta = pose
    xy = 0.5 * (cov[:2, :2] + cov[:2, :2].T)
    values, vectors = np.linalg.eigh(xy)
    if not np.all(np.isfinite(values)):
        return
    radii = np.sqrt(CHI2_2D_95 * np.clip(values, 0.0, None))
    t = np.linspace(0.0, 2.0 * math.pi, ELLIPSE_POINTS, endpoint=False)
    ring = (vectors @ (radii[:, None] * np.vstack([np.cos(t), np.sin(t)]))).T + (x, y)
    pts = camera.points_to_screen(ring)
    if prim.on_surface(surface, pts, 2.0) and np.abs(pts).max() < 1e6:
        pygame.draw.aalines(surface, colour, True, [tuple(p) for p in pts.tolist()])
    spread = Z_95 * math.sqrt(max(float(cov[2, 2]), 0.0))
    if spread < math.pi:
        centre = camera.to_screen(x, y)
        reach = max(camera.length(0.3), 12.0)  # [px]
        for a in (theta - spread, theta + spread):
            prim.line(surface, pal.mix(colour, pal.FLOOR, 0.4), centre,
                      (centre[0] + reach * math.cos(a), centre[1] - reach * math.sin(a)), 1)
