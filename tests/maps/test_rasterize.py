"""The scenario rasteriser: a cell is occupied when its centre is inside an obstacle; obstacles
too thin for that still leave a closed line of cells."""
from __future__ import annotations

import math

import numpy as np
import pytest

from pymunk_bot.config import parse_scenario
from pymunk_bot.maps.rasterize import scenario_grid

RES = 0.05  # [m]


def _grid(obstacles, resolution: float = RES):
    config = parse_scenario({"name": "r", "world": {"size": [4.0, 3.0]}, "obstacles": obstacles,
                             "robots": [{"name": "r1", "pose": [0.4, 0.4, 0.0]}]}, "test")
    return scenario_grid(config, resolution)


def _occupied_at(grid, xy) -> np.ndarray:
    row, col = grid.cell_of(np.asarray(xy, dtype=float))
    return grid.data[row, col] == 100


def test_a_box_covers_exactly_the_cells_whose_centres_it_holds():
    # 1.0 x 0.6 m box whose edges lie 0.01 m past cell boundaries: centre rule, no growth
    grid = _grid([{"type": "box", "center": [2.01, 1.51], "size": [1.0, 0.6]}])
    xs, ys = grid.cell_centers()
    inside = np.logical_and.outer(np.abs(ys - 1.51) <= 0.3, np.abs(xs - 2.01) <= 0.5)
    interior = np.zeros_like(inside)
    interior[np.ix_((ys > 0) & (ys < 3.0), (xs > 0) & (xs < 4.0))] = True
    occupied = grid.data == 100
    assert np.array_equal(occupied & interior, inside)
    assert inside.sum() == 20 * 12  # 1.0 / 0.05 by 0.6 / 0.05: the box's own area


def test_arena_walls_follow_the_same_rule():
    grid = _grid([])
    assert not _occupied_at(grid, [0.01, 1.5]) and _occupied_at(grid, [-0.01, 1.5])
    assert not _occupied_at(grid, [3.99, 1.5]) and _occupied_at(grid, [4.01, 1.5])


def test_a_wall_one_and_a_half_cells_thick_is_not_widened():
    grid = _grid([{"type": "wall", "start": [2.0, 0.0], "end": [2.0, 3.0], "thickness": 0.1}])
    row = grid.data[grid.cell_of(np.array([1.0, 1.5]))[0]]
    assert (row[(grid.cell_centers()[0] > 1.0) & (grid.cell_centers()[0] < 3.0)] == 100).sum() == 2


@pytest.mark.parametrize("angle", [0.0, 0.3, math.pi / 4, 1.2])
def test_a_wall_thinner_than_a_cell_is_a_closed_line(angle):
    centre, half = np.array([2.0, 1.5]), 1.0
    d = np.array([math.cos(angle), math.sin(angle)])
    a, b = centre - half * d, centre + half * d
    grid = _grid([{"type": "wall", "start": a.tolist(), "end": b.tolist(), "thickness": 0.01}])
    occupied = grid.data == 100
    assert 0 < occupied[grid.cell_of(np.array([[2.0, 1.5]]))].sum()
    # walking across the wall at fine steps, every crossing meets an occupied cell or steps
    # between two diagonal ones (8-connected): no ray slips through
    normal = np.array([-d[1], d[0]])
    for s in np.linspace(-0.9, 0.9, 37):
        pts = centre + s * d + np.linspace(-0.2, 0.2, 161)[:, None] * normal
        rows, cols = grid.cell_of(pts)
        assert occupied[rows, cols].any()
    # and the line is no wider than the wall needs: under 2 cells per cell of length
    assert occupied[np.ix_(np.arange(20, 40), np.arange(20, 40))].sum() < 200


def test_a_post_narrower_than_a_cell_marks_its_cell():
    grid = _grid([{"type": "circle", "center": [1.01, 1.01], "radius": 0.01}])
    assert _occupied_at(grid, [1.01, 1.01])
    interior = (grid.data == 100)[4:-4, 4:-4]  # away from the arena walls
    assert interior.sum() == 1


def test_a_round_post_covers_its_area():
    grid = _grid([{"type": "circle", "center": [2.0, 1.5], "radius": 0.3}])
    xs, ys = grid.cell_centers()
    inside = np.add.outer((ys - 1.5) ** 2, (xs - 2.0) ** 2) <= 0.09
    interior = (grid.data == 100)[4:-4, 4:-4]
    assert interior.sum() == inside.sum()
    assert inside.sum() * RES ** 2 == pytest.approx(math.pi * 0.09, rel=0.05)
