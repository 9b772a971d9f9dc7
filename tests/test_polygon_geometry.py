"""The geometry layer on shapely (issue 24): hand-computed cases for what validation relies on."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from pymunk_bot.geometry import plane as geo
from pymunk_bot.cli import main
from pymunk_bot.config.schema import BoxObstacle, PolygonObstacle
from pymunk_bot.config.outlines import distance_to_obstacle, footprint_hits
from pymunk_bot.geometry.footprint import Footprint, polygon_centroid

# An L: a 2 m x 0.5 m foot and a 0.5 m x 2 m upright, its inner corner at (0.5, 0.5).
L_SHAPE = np.array([[0, 0], [2, 0], [2, 0.5], [0.5, 0.5], [0.5, 2], [0, 2]], dtype=float)


def _validate(capsys, tmp_path: Path, data: dict) -> str:
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump({"name": "s", "world": {"size": [6.0, 4.0]}, **data}))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith(f"error: {path}") and "Traceback" not in err, err
    return err


def test_a_bow_tie_obstacle_names_where_its_edges_cross(tmp_path, capsys):
    err = _validate(capsys, tmp_path, {
        "obstacles": [{"type": "polygon", "points": [[1, 1], [2, 2], [2, 1], [1, 2]]}],
        "robots": [{"name": "r", "pose": [4.0, 2.0, 0.0]}]})
    # the diagonals (1,1)-(2,2) and (2,1)-(1,2) cross at their middles
    assert "obstacles[0].points: degenerate polygon: edges cross each other at (1.5, 1.5)" in err


def test_a_footprint_through_a_repeated_point_names_the_point(tmp_path, capsys):
    points = [[-0.2, -0.2], [0, 0], [0.2, -0.2], [0.2, 0.2], [0, 0], [-0.2, 0.2]]
    footprint = {"type": "polygon", "points": points}
    err = _validate(capsys, tmp_path, {"robots": [
        {"name": "r", "pose": [2.0, 2.0, 0.0], "footprint": footprint}]})
    assert "robots[0].footprint.points: degenerate polygon: the outline touches itself at (0, 0)" \
        in err


@pytest.mark.parametrize("points, words", [
    ([[0, 0], [1, 0], [2, 0]], "zero area"),
    ([[0, 0], [1, 0], [1, 0], [0, 1]], "point 1 repeats its neighbour"),
    ([[0, 0], [2, 0], [2, 2], [1, 0], [0, 2]], "touches itself at (1, 0)"),  # vertex on an edge
    ([[0, 0], [2, 0], [2, 2], [1, 1e-12], [0, 2]], "touches itself at (1, 0)"),  # a pinch
])
def test_polygon_problems_say_what_and_where(points, words):
    assert words in geo.polygon_problem(np.array(points, dtype=float))


def test_a_simple_concave_polygon_has_no_problem():
    assert geo.polygon_problem(L_SHAPE) is None
    assert geo.polygon_problem(L_SHAPE[::-1]) is None  # clockwise is fine too


def test_two_robots_with_the_same_outline_on_the_same_spot_overlap(tmp_path, capsys):
    # Equal outlines share all their area though no edge crosses another (this was let through).
    box = {"type": "polygon", "points": [[-0.3, -0.2], [0.3, -0.2], [0.3, 0.2], [-0.3, 0.2]]}
    err = _validate(capsys, tmp_path, {"robots": [
        {"name": "a", "pose": [2.0, 2.0, 0.0], "footprint": box},
        {"name": "b", "pose": [2.0, 2.0, 0.0], "footprint": box}]})
    assert "robots[1].pose: robot overlaps robots[0] (a)" in err


def test_overlap_means_shared_area_not_a_shared_edge():
    unit = geo.box_corners((0.0, 0.0), (1.0, 1.0))
    assert geo.polygons_overlap(unit, unit)
    assert not geo.polygons_overlap(unit, unit + (1.0, 0.3))  # side by side, touching
    assert geo.polygons_overlap(unit, unit + (0.999, 0.3))
    assert geo.polygons_overlap(unit, 0.25 * unit[::-1])  # inside, other winding


def test_an_l_shaped_footprint_keeps_its_clearance_to_a_box_in_its_notch():
    """A 1 m box in the L's notch, moved t along the diagonal toward its inner corner: its
    sides are 0.5 - t from the L's inner faces, so it touches at t = 0.5 (its bounding disc
    overlaps the L long before)."""
    footprint = Footprint("polygon", polygon_centroid(L_SHAPE), 3.0, L_SHAPE)
    for t, hits in ((0.45, False), (0.55, True)):
        box = BoxObstacle(type="box", center=[1.5 - t, 1.5 - t], size=[1.0, 1.0])
        assert footprint_hits(footprint, (0.0, 0.0, 0.0), box) is hits
        gap = max(0.0, 0.5 - t)  # from the box's corner, nearest to the L's faces
        assert geo.distance_to_polygon((1.0 - t, 1.0 - t), L_SHAPE) == pytest.approx(gap)
    # turned a quarter turn clockwise about the pose point, its upright lies along y = -2..0
    box = BoxObstacle(type="box", center=[0.25, -1.0], size=[0.2, 0.2])
    assert footprint_hits(footprint, (0.0, 0.0, -math.pi / 2), box)
    assert not footprint_hits(footprint, (0.0, 0.0, 0.0), box)


def test_distances_to_an_l_shaped_obstacle():
    wall = PolygonObstacle(type="polygon", points=L_SHAPE.tolist())
    assert distance_to_obstacle((1.0, 1.0), wall) == pytest.approx(0.5)  # over the notch
    assert distance_to_obstacle((0.25, 1.0), wall) == 0.0  # inside the upright
    assert distance_to_obstacle((3.0, 0.25), wall) == pytest.approx(1.0)
    assert geo.point_in_polygon((0.5, 1.0), L_SHAPE)  # on the outline counts as inside
    assert not geo.point_in_polygon((1.0, 1.0), L_SHAPE)


def test_thinness_is_the_thinnest_part_across_a_vertex():
    assert geo.thinness(geo.box_corners((3.0, 1.0), (2.0, 0.3), 0.7)) == pytest.approx(0.3)
    assert geo.thinness(L_SHAPE) == pytest.approx(0.5)  # an arm, not the hull's 2 m x 2 m
    many = geo.thinnesses([L_SHAPE, geo.box_corners((0, 0), (1.0, 0.2))])
    assert many == pytest.approx([0.5, 0.2])


def test_centroid_of_the_l():
    # foot: area 1 at (1, 0.25); upright above it: area 0.75 at (0.25, 1.25)
    x, y = polygon_centroid(L_SHAPE)
    assert (x, y) == pytest.approx(((1.0 + 0.75 * 0.25) / 1.75, (0.25 + 0.75 * 1.25) / 1.75))
