"""Antialiased drawing helpers on top of pygame.draw / pygame.gfxdraw, safe at any zoom.

gfxdraw takes 16-bit coordinates, so shapes far outside the surface (deep zoom) fall back to
pygame.draw, which clips them itself.
"""
from __future__ import annotations

import math

import numpy as np
import pygame
import pygame.gfxdraw

_GFX_LIMIT = 30_000  # [px]; gfxdraw's coordinates are signed 16-bit


def on_surface(surface: pygame.Surface, points: np.ndarray, pad: float = 0.0) -> bool:
    """Whether the bounding box of ``points`` (N, 2) [px] overlaps the surface (grown by pad)."""
    w, h = surface.get_size()
    lo, hi = points.min(axis=0), points.max(axis=0)
    return bool(hi[0] >= -pad and hi[1] >= -pad and lo[0] <= w + pad and lo[1] <= h + pad)


def polygon(surface: pygame.Surface, fill, edge, points: np.ndarray) -> None:
    """A filled polygon with an antialiased outline; ``points`` (N, 2) [px]."""
    if len(points) < 3 or not on_surface(surface, points, 2.0):
        return
    pts = [(float(x), float(y)) for x, y in points]
    if np.abs(points).max() < _GFX_LIMIT:
        ipts = [(int(round(x)), int(round(y))) for x, y in pts]
        pygame.gfxdraw.filled_polygon(surface, ipts, fill)
    else:
        pygame.draw.polygon(surface, fill, pts)
    pygame.draw.aalines(surface, edge if edge is not None else fill, True, pts)


def circle(surface: pygame.Surface, fill, edge, centre: tuple[float, float], radius: float) -> None:
    """A filled circle with an antialiased rim (``fill`` None: rim only)."""
    cx, cy = centre
    w, h = surface.get_size()
    if cx + radius < -2 or cy + radius < -2 or cx - radius > w + 2 or cy - radius > h + 2:
        return
    r = max(radius, 1.0)
    if max(abs(cx), abs(cy)) + r < _GFX_LIMIT:
        ix, iy, ir = int(round(cx)), int(round(cy)), int(round(r))
        if fill is not None:
            pygame.gfxdraw.filled_circle(surface, ix, iy, ir, fill)
        pygame.gfxdraw.aacircle(surface, ix, iy, ir, edge if edge is not None else fill)
    else:
        if fill is not None:
            pygame.draw.circle(surface, fill, (cx, cy), r)
        if edge is not None:
            pygame.draw.circle(surface, edge, (cx, cy), r, 1)


def ring(surface: pygame.Surface, colour, centre: tuple[float, float], radius: float,
         width: int = 2) -> None:
    """An antialiased ring ``width`` pixels wide."""
    for k in range(width):
        circle(surface, None, colour, centre, radius + k)


def line(surface: pygame.Surface, colour, a, b, width: float = 1.0) -> None:
    """An antialiased line; wider than 1.5 px it is drawn as a thin filled quad."""
    if width <= 1.5:
        pygame.draw.aaline(surface, colour, a, b)
        return
    dx, dy = b[0] - a[0], b[1] - a[1]
    length = math.hypot(dx, dy)
    if length < 1e-9:
        return
    nx, ny = -dy / length * width / 2, dx / length * width / 2
    quad = np.array([(a[0] + nx, a[1] + ny), (b[0] + nx, b[1] + ny),
                     (b[0] - nx, b[1] - ny), (a[0] - nx, a[1] - ny)])
    polygon(surface, colour, colour, quad)


def polyline(surface: pygame.Surface, colour, points: np.ndarray, width: int = 1) -> None:
    """An open antialiased polyline through ``points`` (N, 2) [px]."""
    if len(points) < 2 or not on_surface(surface, points, width):
        return
    pts = [(float(x), float(y)) for x, y in points]
    if width > 1:
        pygame.draw.lines(surface, colour, False, pts, width)
    pygame.draw.aalines(surface, colour, False, pts)


def dashed_polyline(surface: pygame.Surface, colour, points: np.ndarray, dash: float = 8.0,
                    gap: float = 6.0) -> None:
    """A dashed polyline: dashes of ``dash`` px every ``dash + gap`` px along the path."""
    if len(points) < 2 or not on_surface(surface, points):
        return
    seg = np.hypot(*np.diff(points, axis=0).T)
    s = np.concatenate(([0.0], np.cumsum(seg)))
    if s[-1] <= 0:
        return
    starts = np.arange(0.0, s[-1], dash + gap)
    ends = np.minimum(starts + dash, s[-1])
    xs0, ys0 = np.interp(starts, s, points[:, 0]), np.interp(starts, s, points[:, 1])
    xs1, ys1 = np.interp(ends, s, points[:, 0]), np.interp(ends, s, points[:, 1])
    for x0, y0, x1, y1 in zip(xs0, ys0, xs1, ys1):
        pygame.draw.aaline(surface, colour, (x0, y0), (x1, y1))


def dashed_ring(surface: pygame.Surface, colour, centre: tuple[float, float], radius: float,
                dashes: int = 16) -> None:
    """A circle drawn as ``dashes`` arcs with gaps between them."""
    cx, cy = centre
    n = dashes * 4
    angles = np.linspace(0.0, 2 * math.pi, n + 1)
    xs, ys = cx + radius * np.cos(angles), cy + radius * np.sin(angles)
    for k in range(0, n, 4):
        pts = list(zip(xs[k:k + 3].tolist(), ys[k:k + 3].tolist()))
        pygame.draw.aalines(surface, colour, False, pts)
