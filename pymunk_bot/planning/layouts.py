"""Random layouts (mazes, cluttered fields) as scenario obstacle lists, drawn from a seed.

Used to test controllers on layouts they were not tuned on, and to write the shipped maze and
clutter scenarios. Everything is drawn from the numpy Generator passed in.
"""
from __future__ import annotations

import math

import numpy as np


def maze_walls(rng: np.random.Generator, cols: int, rows: int, cell: float,
               thickness: float = 0.1, extra_openings: float = 0.0) -> list[dict]:
    """A perfect maze (recursive backtracker) of ``cols`` x ``rows`` cells of ``cell`` metres.

    Returns wall obstacles for the inner walls only (the arena walls close the outside), with
    collinear neighbours merged into one wall. ``extra_openings`` is the fraction of the
    remaining inner walls knocked out afterwards, which makes loops (several routes).
    """
    # east[r][c]: wall between (r, c) and (r, c+1); north[r][c]: between (r, c) and (r+1, c)
    east = np.ones((rows, cols - 1), dtype=bool)
    north = np.ones((rows - 1, cols), dtype=bool)
    seen = np.zeros((rows, cols), dtype=bool)
    stack = [(int(rng.integers(rows)), int(rng.integers(cols)))]
    seen[stack[0]] = True
    while stack:
        r, c = stack[-1]
        options = [(dr, dc) for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0))
                   if 0 <= r + dr < rows and 0 <= c + dc < cols and not seen[r + dr, c + dc]]
        if not options:
            stack.pop()
            continue
        dr, dc = options[int(rng.integers(len(options)))]
        if dc:
            east[r, min(c, c + dc)] = False
        else:
            north[min(r, r + dr), c] = False
        seen[r + dr, c + dc] = True
        stack.append((r + dr, c + dc))
    if extra_openings > 0:
        east &= rng.random(east.shape) >= extra_openings
        north &= rng.random(north.shape) >= extra_openings
    walls: list[dict] = []
    # Merge runs of vertical walls (east sides) along each column line, and horizontal ones.
    for c in range(cols - 1):
        walls += _runs(east[:, c], lambda r0, r1, c=c: ((c + 1) * cell, r0 * cell),
                       lambda r0, r1, c=c: ((c + 1) * cell, r1 * cell), thickness)
    for r in range(rows - 1):
        walls += _runs(north[r, :], lambda c0, c1, r=r: (c0 * cell, (r + 1) * cell),
                       lambda c0, c1, r=r: (c1 * cell, (r + 1) * cell), thickness)
    return walls


def _runs(mask: np.ndarray, start_of, end_of, thickness: float) -> list[dict]:
    walls = []
    k = 0
    n = len(mask)
    while k < n:
        if not mask[k]:
            k += 1
            continue
        k0 = k
        while k < n and mask[k]:
            k += 1
        walls.append({"type": "wall", "start": [round(v, 4) for v in start_of(k0, k)],
                      "end": [round(v, 4) for v in end_of(k0, k)], "thickness": thickness})
    return walls


def clutter(rng: np.random.Generator, size: tuple[float, float], count: int,
            keep_clear: list[tuple[float, float, float]], min_gap: float,
            radius_range: tuple[float, float] = (0.15, 0.35), box_fraction: float = 0.5,
            max_tries: int = 20000) -> list[dict]:
    """``count`` random circles and boxes, ``min_gap`` [m] apart (gap between their bounding
    circles) and outside every keep-clear disc (x, y, radius), e.g. around starts and goals."""
    placed: list[tuple[float, float, float]] = []
    obstacles: list[dict] = []
    width, height = size
    tries = 0
    while len(obstacles) < count and tries < max_tries:
        tries += 1
        r = float(rng.uniform(*radius_range))
        x = float(rng.uniform(r, width - r))
        y = float(rng.uniform(r, height - r))
        if any(math.hypot(x - kx, y - ky) < r + kr for kx, ky, kr in keep_clear):
            continue
        if any(math.hypot(x - px, y - py) < r + pr + min_gap for px, py, pr in placed):
            continue
        placed.append((x, y, r))
        if rng.random() < box_fraction:
            side = r * math.sqrt(2.0)  # the box fits inside its bounding circle
            obstacles.append({"type": "box", "center": [round(x, 3), round(y, 3)],
                              "size": [round(side, 3), round(side, 3)],
                              "angle": round(float(rng.uniform(0, math.pi / 2)), 3)})
        else:
            obstacles.append({"type": "circle", "center": [round(x, 3), round(y, 3)],
                              "radius": round(r, 3)})
    return obstacles
