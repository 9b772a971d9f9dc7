"""The compiled A* against an independent reference: scipy's Dijkstra over the same graph
(8-connected cells, a step costing its length times the mean of its cells' cost multipliers,
no corner cutting). A*'s tie-break inflates the octile heuristic by 1e-4, so its path may cost
at most that much more than the cheapest."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from pymunk_bot.config.loader import parse_scenario
from pymunk_bot.planning import ClearanceGrid, MapInfo, astar
from pymunk_bot.planning.astar import cost_multipliers
from pymunk_bot.planning.layouts import maze_walls


def cheapest(multiplier: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> float:
    """The least cost (in cells) from start to goal cell, by Dijkstra."""
    rows, cols = multiplier.shape
    index = np.arange(rows * cols).reshape(rows, cols)
    free = np.isfinite(multiplier)
    a, b, w = [], [], []
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
        r0, r1 = max(0, -dr), rows - max(0, dr)
        c0, c1 = max(0, -dc), cols - max(0, dc)
        here = (slice(r0, r1), slice(c0, c1))
        there = (slice(r0 + dr, r1 + dr), slice(c0 + dc, c1 + dc))
        ok = free[here] & free[there]
        if dr and dc:  # no corner cutting: both side cells free too
            ok &= free[r0 + dr:r1 + dr, c0:c1] & free[r0:r1, c0 + dc:c1 + dc]
        cost = 0.5 * (multiplier[here] + multiplier[there]) * math.hypot(dr, dc)
        a.append(index[here][ok]), b.append(index[there][ok]), w.append(cost[ok])
    a, b, w = np.concatenate(a), np.concatenate(b), np.concatenate(w)
    graph = coo_matrix((np.concatenate([w, w]), (np.concatenate([a, b]), np.concatenate([b, a]))),
                       shape=(rows * cols, rows * cols)).tocsr()
    return float(dijkstra(graph, indices=index[start])[index[goal]])


def maze_grid(seed: int) -> ClearanceGrid:
    walls = maze_walls(np.random.default_rng(seed), 7, 7, 1.0, 0.1, extra_openings=0.2)
    config = parse_scenario({"name": "m", "world": {"size": [7.0, 7.0]}, "obstacles": walls,
                             "robots": [{"name": "r", "pose": [0.3, 0.3, 0.0]}]}, "test")
    return ClearanceGrid.from_map(MapInfo.from_scenario(config), 0.1, 0.6)


@pytest.mark.parametrize("seed", range(4))
def test_astar_paths_cost_what_dijkstra_finds_cheapest(seed):
    grid = maze_grid(seed)
    rng = np.random.default_rng(seed)
    hard, soft, weight = 0.22, 0.45, 4.0
    multiplier = cost_multipliers(grid.clearance, hard, soft, weight)
    checked = 0
    while checked < 5:
        (sx, sy), (gx, gy) = rng.uniform(0.3, 6.7, size=(2, 2))
        start, goal = grid.cell_of(sx, sy), grid.cell_of(gx, gy)
        if not (np.isfinite(multiplier[start]) and np.isfinite(multiplier[goal])):
            continue
        result = astar(grid, (sx, sy), (gx, gy), hard, soft, weight)
        best = cheapest(multiplier, start, goal) * grid.resolution
        if not math.isfinite(best):
            assert not result.found
            continue
        assert result.found and result.cost == pytest.approx(best, rel=1.5e-4)
        assert result.cost >= best - 1e-9
        checked += 1
