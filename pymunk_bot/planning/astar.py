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

import numba
import numpy as np

from pymunk_bot.planning.grid import ClearanceGrid

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
    """A* on a flat, padded copy of the grid (compiled: :func:`_expand`)."""
    rows, cols = multiplier.shape
    width = cols + 2  # one blocked cell of padding on every side: no bounds checks
    padded = np.full((rows + 2, width), np.inf)
    padded[1:-1, 1:-1] = multiplier
    cost = padded.ravel()
    s = (start[0] + 1) * width + start[1] + 1
    g_idx = (goal[0] + 1) * width + goal[1] + 1
    best = np.full(len(cost), np.inf)
    parent = np.full(len(cost), -1, dtype=np.int64)
    result.expanded = int(_expand(cost, width, s, g_idx, best, parent))
    if not np.isfinite(best[g_idx]):
        return None
    result.cost = float(best[g_idx])
    cells = []
    i = g_idx
    while i != -1:
        r, c = divmod(int(i), width)
        cells.append((r - 1, c - 1))
        i = parent[i]
    cells.reverse()
    return cells


@numba.njit(cache=True, nogil=True, inline="always")
def _heuristic(i: int, goal_row: int, goal_col: int, width: int) -> float:
    """Octile distance from cell ``i`` to the goal, in cells; the tiny tie-break toward the
    goal makes A* expand far fewer equal-cost cells."""
    dr, dc = abs(i // width - goal_row), abs(i % width - goal_col)
    return (max(dr, dc) + (SQRT2 - 1.0) * min(dr, dc)) * (1.0 + 1e-4)


@numba.njit(cache=True, nogil=True)
def _expand(cost: np.ndarray, width: int, s: int, g_idx: int, best: np.ndarray,
            parent: np.ndarray) -> int:  # pragma: no cover - compiled
    """The A* loop: fills ``best`` (cost so far) and ``parent``; returns the cells expanded
    (taken off the open list), the search stopping once the goal is (its best is then final).
    Ties break as Python's heapq of (f, g, cell) tuples does."""
    inf = np.inf
    n = len(cost)
    goal_row, goal_col = g_idx // width, g_idx % width
    closed = np.zeros(n, dtype=np.uint8)
    best[s] = 0.0
    open_list = [(_heuristic(s, goal_row, goal_col, width), 0.0, s)]
    straight = ((1, 1.0), (-1, 1.0), (width, 1.0), (-width, 1.0))
    diagonal = ((width + 1, 1, width), (width - 1, -1, width),
                (-width + 1, 1, -width), (-width - 1, -1, -width))
    expanded = 0
    goal_closed = False
    while open_list:
        _, g, i = heapq.heappop(open_list)
        if closed[i]:
            continue
        closed[i] = 1
        expanded += 1
        if i == g_idx:
            goal_closed = True
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
                heapq.heappush(open_list, (ng + _heuristic(j, goal_row, goal_col, width),
                                           ng, j))
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
                heapq.heappush(open_list, (ng + _heuristic(j, goal_row, goal_col, width),
                                           ng, j))
    if not goal_closed:
        best[g_idx] = inf
    return expanded
