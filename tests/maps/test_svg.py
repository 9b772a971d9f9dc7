"""SVG floor plans: shapes, transforms, curves within 1 cm, strokes as walls, errors."""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest
from map_helpers import cast

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.maps.files import load_world_map
from pymunk_bot.maps.outlines import add_to_space, free_disc

HEAD = '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1000 500">'


def _plan(tmp_path, body: str, head: str = HEAD, scale: float | None = 0.01):
    path = tmp_path / "plan.svg"
    path.write_text(head + body + "</svg>")
    geometry = load_world_map(path, scale, source="scen.yaml")
    space = pymunk.Space()
    add_to_space(space, geometry)
    return geometry, space


def test_rect_circle_polygon_with_y_flipped_and_scaled(tmp_path):
    geometry, space = _plan(tmp_path, '<rect x="100" y="100" width="200" height="100"/>'
                                      '<circle cx="600" cy="250" r="50"/>'
                                      '<polygon points="800,400 900,400 850,300"/>')
    assert geometry.extent == (0.0, 0.0, 10.0, 5.0)
    # rect: user y 100..200 -> world y 3..4 (y flipped), x 1..3
    assert cast(space, (2.0, 0.5), math.pi / 2) == pytest.approx(3.0 - 0.5, abs=1e-9)
    assert cast(space, (0.5, 3.5), 0.0) == pytest.approx(0.5, abs=1e-9)
    # circle centre (6, 2.5), radius 0.5: sampled within 1 cm
    for angle in np.linspace(0, 2 * math.pi, 17):
        origin = (6 + 1.5 * math.cos(angle), 2.5 + 1.5 * math.sin(angle))
        assert cast(space, origin, angle + math.pi) == pytest.approx(1.0, abs=0.01)
    # triangle: apex at user (850, 300) -> world (8.5, 2.0), base at world y 1.0
    assert cast(space, (8.5, 0.2), math.pi / 2) == pytest.approx(0.8, abs=1e-9)
    assert cast(space, (8.5, 4.5), -math.pi / 2) == pytest.approx(2.5, abs=1e-9)
    assert not free_disc(geometry, 2.0, 3.5, 0.1) and free_disc(geometry, 2.0, 2.5, 0.3)


def test_transforms_on_groups_and_shapes(tmp_path):
    geometry, space = _plan(tmp_path, '<g transform="translate(500 250) rotate(45)">'
                                      '<rect x="-100" y="-100" width="200" height="200"/></g>')
    # a 2 m square rotated 45 degrees about world (5, 2.5): its corner is sqrt(2) from the centre
    assert cast(space, (0.5, 2.5), 0.0) == pytest.approx(4.5 - math.sqrt(2), abs=1e-6)


def test_ellipse_and_bezier_path_within_a_centimetre(tmp_path):
    geometry, space = _plan(
        tmp_path, '<ellipse cx="300" cy="250" rx="200" ry="100"/>'
                  '<path d="M 600 400 Q 750 100 900 400 Z"/>')
    for angle in np.linspace(0.1, 2 * math.pi, 13):
        # the ellipse boundary point in this direction from its centre (3, 2.5)
        c, s = math.cos(angle), math.sin(angle)
        r = 1.0 / math.hypot(c / 2.0, s / 1.0)
        assert cast(space, (3 + 2.2 * c, 2.5 + 2.2 * s), angle + math.pi) == pytest.approx(2.2 - r,
                                                                            abs=0.01)
    # quadratic Bezier apex: B(0.5) = (750, 250) -> world (7.5, 2.5); base at world y 1.0
    assert cast(space, (7.5, 4.9), -math.pi / 2) == pytest.approx(2.4, abs=0.01)
    assert cast(space, (7.5, 0.2), math.pi / 2) == pytest.approx(0.8, abs=1e-9)


def test_strokes_are_walls_of_their_width_and_unfilled_outlines_stay_open(tmp_path):
    geometry, space = _plan(
        tmp_path, '<line x1="200" y1="0" x2="200" y2="300" stroke="black" stroke-width="10"/>'
                  '<rect x="500" y="100" width="300" height="300" fill="none" stroke="#333" '
                  'stroke-width="4"/>')
    assert cast(space, (0.5, 4.0), 0.0) == pytest.approx(2.0 - 0.05 - 0.5, abs=1e-9)
    assert cast(space, (0.5, 1.0), 0.0) == pytest.approx(5.0 - 0.02 - 0.5, abs=1e-9)  # below the line
    assert free_disc(geometry, 6.5, 2.5, 0.3)  # inside the unfilled room
    assert cast(space, (6.5, 2.5), 0.0) == pytest.approx(1.5 - 0.02, abs=1e-9)


def test_filled_ring_keeps_its_hole_free(tmp_path):
    geometry, space = _plan(tmp_path, '<path fill-rule="evenodd" d="M 100 50 H 900 V 450 H 100 Z '
                                      'M 150 100 H 850 V 400 H 150 Z"/>')
    assert free_disc(geometry, 5.0, 2.5, 0.5)
    assert not free_disc(geometry, 1.25, 2.5, 0.1)  # in the ring's material
    assert cast(space, (5.0, 2.5), 0.0) == pytest.approx(3.5, abs=1e-9)


def test_plan_without_viewbox_uses_its_size_and_map_scale(tmp_path):
    head = '<svg xmlns="http://www.w3.org/2000/svg" width="400" height="200">'
    geometry, space = _plan(tmp_path, '<rect x="0" y="0" width="100" height="100"/>', head, 0.05)
    assert geometry.extent == (0.0, 0.0, 20.0, 10.0)
    assert cast(space, (2.5, 1.0), math.pi / 2) == pytest.approx(4.0, abs=1e-9)  # rect y 5..10 m


@pytest.mark.parametrize("body, message", [
    ("", "nothing to build a map from"),
    ('<rect x="0" y="0" width="10" height="10" fill="none"/>', "nothing to build a map from"),
])
def test_empty_plans_are_bad_input(tmp_path, body, message):
    with pytest.raises(ScenarioError, match=message) as info:
        _plan(tmp_path, body)
    assert str(info.value).startswith("scen.yaml: world.map: ")


def test_bad_files_and_scale(tmp_path):
    with pytest.raises(ScenarioError, match="map file not found"):
        load_world_map(tmp_path / "none.svg", source="scen.yaml")
    (tmp_path / "bad.svg").write_text("<svg><rect")
    with pytest.raises(ScenarioError, match="cannot read the SVG"):
        load_world_map(tmp_path / "bad.svg", source="scen.yaml")
    with pytest.raises(ScenarioError, match="world.map_scale: must be a number > 0"):
        load_world_map(tmp_path / "bad.svg", -1.0, source="scen.yaml")
    with pytest.raises(ScenarioError, match="unknown map format '.png'"):
        load_world_map(tmp_path / "plan.png", source="scen.yaml")
    (tmp_path / "m.yaml").write_text("image: m.pgm\n")
    with pytest.raises(ScenarioError, match="world.map_scale: applies to SVG maps only"):
        load_world_map(tmp_path / "m.yaml", 0.01, source="scen.yaml")
