"""A* on a clearance grid, 8-connected, with a cost that keeps paths away from obstacles.

A cell is blocked when its clearance is below ``hard`` (the robot radius plus a small margin).
Between ``hard`` and ``soft`` a cell costs extra, growing quadratically toward ``hard`` (the
inflation cost of ROS costmaps): paths keep ``soft`` clearance where the room allows and still
squeeze through a doorway barely wider than the robot. The octile distance is an admissible
heuristic because every step costs at least its length.
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

import numpy as np

from .grid import ClearanceGrid

SQRT2 = math.sqrt(2.0)


@dataclass
class PlanResult:
    """A path in world metres from start to goal, or None with the reason."""

    path: list[tuple[float, float]] | None
    reason: str = ""
    expanded: int = 0  # cells taken off the open list
    cost: float = math.inf  # [m], length weighted by the clearance cost
    notes: list[str] = field(default_factory=list)

    @property
    def found(self) -> bool:
        return self.path is not None


def cost_multipliers(clearance: np.ndarray, hard: float, soft: float, weight: float) -> np.ndarray:
    """Per-cell cost per metre: inf when blocked, 1 beyond ``soft``, up to 1 + weight at ``hard``."""
    span = max(soft - hard, 1e-9)
    closeness = np.clip((soft - clearance) / span, 0.0, 1.0)
    multiplier = 1.0 + weight * closeness ** 2
    multiplier[clearance < hard] = np.inf
    return multiplier


def nearest_free_cell(free: np.ndarray, grid: ClearanceGrid, x: float, y: float,
                      radius: float) -> tuple[int, int] | None:
    """The free cell nearest to (x, y) within ``radius`` [m], or None."""
    row, col = grid.cell_of(x, y)
    reach = max(1, math.ceil(radius / grid.resolution))
    r0, r1 = max(0, row - reach), min(grid.rows, row + reach + 1)
    c0, c1 = max(0, col - reach), min(grid.cols, col + reach + 1)
    window = free[r0:r1, c0:c1]
    if not window.any():
        return None
    d2 = np.add.outer((grid.ys[r0:r1] - y) ** 2, (grid.xs[c0:c1] - x) ** 2)
    d2[~window] = np.inf
    i, j = np.unravel_index(int(np.argmin(d2)), d2.shape)
    if d2[i, j] > radius * radius:
        return None
    return r0 + int(i), c0 + int(j)


def astar(grid: ClearanceGrid, start, goal, hard: float, soft: float, weight: float = 4.0,
          goal_radius: float = 0.0, start_escape: float = 0.6) -> PlanResult:
    """Cheapest 8-connected path from ``start`` to ``goal`` (world points) through free cells.

    If the start cell is blocked (the robot is already closer to something than ``hard``) the
    path first leaves to the nearest free cell within ``start_escape`` [m]. If the goal cell is
    blocked, any free cell within ``goal_radius`` [m] of the goal will do.
    """
    multiplier = cost_multipliers(grid.clearance, hard, soft, weight)
    free = np.isfinite(multiplier)
    sx, sy = float(start[0]), float(start[1])
    gx, gy = float(goal[0]), float(goal[1])
    result = PlanResult(None)
    start_cell = grid.cell_of(sx, sy)
    if not free[start_cell]:
        escape_cell = nearest_free_cell(free, grid, sx, sy, start_escape)
        if escape_cell is None:
            result.reason = f"the robot at ({sx:.2f}, {sy:.2f}) is boxed in: no free cell nearby"
            return result
        start_cell = escape_cell
        result.notes.append("start was too close to an obstacle; path leaves it first")
    goal_cell = grid.cell_of(gx, gy)
    if not grid.inside(gx, gy):
        result.reason = f"goal ({gx:.2f}, {gy:.2f}) is outside the arena"
        return result
    if not free[goal_cell]:
        near_goal_cell = nearest_free_cell(free, grid, gx, gy, goal_radius)
        if near_goal_cell is None:
            result.reason = (f"goal ({gx:.2f}, {gy:.2f}) is inside an obstacle or too close to "
                             "one for the robot to reach")
            return result
        goal_cell = near_goal_cell
    cells = _search(multiplier, start_cell, goal_cell, result)
    if cells is None:
        result.reason = f"no path from ({sx:.2f}, {sy:.2f}) to goal ({gx:.2f}, {gy:.2f})"
        return result
    path = [grid.center_of(r, c) for r, c in cells]
    if start_cell == grid.cell_of(sx, sy):
        path[0] = (sx, sy)
    else:
        path.insert(0, (sx, sy))
    if goal_cell == grid.cell_of(gx, gy):
        if len(path) == 1:
            path.append((gx, gy))
        else:
            path[-1] = (gx, gy)
    result.cost *= grid.resolution
    result.path = path
    return result


def _search(multiplier: np.ndarray, start: tuple[int, int], goal: tuple[int, int],
            result: PlanResult) -> list[tuple[int, int]] | None:
    """The A* loop on a flat, padded copy of the grid (plain lists: fastest in CPython)."""
    rows, cols = multiplier.shape
    width = cols + 2  # one blocked cell of padding on every side: no bounds checks
    padded = np.full((rows + 2, width), np.inf)
    padded[1:-1, 1:-1] = multiplier
    cost = padded.ravel().tolist()
    s = (start[0] + 1) * width + start[1] + 1
    g_idx = (goal[0] + 1) * width + goal[1] + 1
    goal_row, goal_col = divmod(g_idx, width)
    inf = math.inf
    straight = ((1, 1.0), (-1, 1.0), (width, 1.0), (-width, 1.0))
    diagonal = ((width + 1, 1, width), (width - 1, -1, width),
                (-width + 1, 1, -width), (-width - 1, -1, -width))
    n = len(cost)
    best = [inf] * n
    best[s] = 0.0
    parent = [-1] * n
    closed = bytearray(n)
    # Octile distance to the goal for every cell, computed once with numpy; the tiny tie-break
    # toward the goal makes A* expand far fewer equal-cost cells.
    r_idx, c_idx = np.divmod(np.arange(n), width)
    dr, dc = np.abs(r_idx - goal_row), np.abs(c_idx - goal_col)
    h = ((np.maximum(dr, dc) + (SQRT2 - 1.0) * np.minimum(dr, dc)) * (1.0 + 1e-4)).tolist()
    open_list = [(h[s], 0.0, s)]
    push, pop = heapq.heappush, heapq.heappop
    expanded = 0
    while open_list:
        _, g, i = pop(open_list)
        if closed[i]:
            continue
        closed[i] = 1
        expanded += 1
        if i == g_idx:
            break
        ci = cost[i]
        for step, length in straight:
            j = i + step
            cj = cost[j]
            if cj == inf or closed[j]:
                continue
            ng = g + 0.5 * (ci + cj) * length
            if ng < best[j]:
                best[j] = ng
                parent[j] = i
                push(open_list, (ng + h[j], ng, j))
        for step, side_a, side_b in diagonal:
            j = i + step
            cj = cost[j]
            # No corner cutting: both cells beside a diagonal move must be free too.
            if cj == inf or closed[j] or cost[i + side_a] == inf or cost[i + side_b] == inf:
                continue
            ng = g + 0.5 * (ci + cj) * SQRT2
            if ng < best[j]:
                best[j] = ng
                parent[j] = i
                push(open_list, (ng + h[j], ng, j))
    result.expanded = expanded
    if not closed[g_idx]:
        return None
    result.cost = best[g_idx]
    cells = []
    i = g_idx
    while i != -1:
        r, c = divmod(i, width)
        cells.append((r - 1, c - 1))
        i = parent[i]
    cells.reverse()
    return cells
