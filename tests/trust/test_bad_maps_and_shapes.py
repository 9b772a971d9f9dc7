"""Inputs that used to crash or stall: each is now one line on stderr and exit 2, within a bound
on the work it may cost (issue 24, items 1-4, and the map and echo messages)."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from pymunk_bot.cli import main
from pymunk_bot.maps import svg
from pymunk_bot.maps.outlines import geometry_from_grid
from pymunk_bot.maps.grid import OccupancyGrid

ROBOT = {"name": "r", "pose": [1.0, 1.0, 0.0]}


def one_line_exit_2(capsys, path: Path, *fragments: str) -> str:
    started = time.process_time()  # CPU time: a loaded machine does not fail it
    assert main(["validate", str(path)]) == 2
    assert time.process_time() - started < 5
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("error: ") and "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in err, err
    return err


def scenario(tmp_path: Path, **data) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump({"name": "s", "robots": [ROBOT], **data}))
    return path


@pytest.mark.parametrize("movable", [True, False])
@pytest.mark.parametrize("points", [
    [[2, 2], [3, 3], [4, 2], [4, 4], [3, 3], [2, 4]],  # touches itself at a repeated point
    [[2, 2], [4, 2], [4, 4], [3, 2], [2, 4]],  # a point lies on another edge
])
def test_a_polygon_that_touches_itself_is_refused(tmp_path, capsys, movable, points):
    path = scenario(tmp_path, world={"size": [6.0, 6.0]},
                    obstacles=[{"type": "polygon", "points": points, "movable": movable}])
    one_line_exit_2(capsys, path, "obstacles[0].points", "touches itself")


def test_a_robot_footprint_that_touches_itself_is_refused(tmp_path, capsys):
    robot = dict(ROBOT, footprint={"type": "polygon", "points": [
        [-0.2, -0.2], [0, 0], [0.2, -0.2], [0.2, 0.2], [0, 0], [-0.2, 0.2]]})
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump({"name": "s", "world": {"size": [4.0, 4.0]},
                                    "robots": [robot]}))
    one_line_exit_2(capsys, path, "robots[0].footprint.points", "touches itself")


@pytest.mark.parametrize("value", [100, -1, 0])
def test_a_map_of_one_kind_of_cell_traces(value):
    grid = OccupancyGrid(np.full((60, 60), value, dtype=np.int8), 0.05, (0.0, 0.0))
    geometry = geometry_from_grid(grid)
    assert geometry.extent == (0.0, 0.0, 3.0, 3.0)


def write_ros_map(folder: Path, image: str = "m.pgm", origin=(0.0, 0.0, 0.0), pixels=0) -> Path:
    Image.fromarray(np.full((60, 60), pixels, dtype=np.uint8)).save(folder / "m.pgm")
    path = folder / "m.yaml"
    path.write_text(yaml.safe_dump({"image": image, "resolution": 0.05, "origin": list(origin)}))
    return path


def test_an_all_occupied_ros_map_is_a_start_error_not_a_crash(tmp_path, capsys):
    write_ros_map(tmp_path)
    path = scenario(tmp_path, world={"map": "m.yaml"})
    one_line_exit_2(capsys, path, "robots[0].pose", "occupied cell")


@pytest.mark.parametrize("image, problem", [
    ("folder.pgm", "is a directory"),
    ("/dev/zero", "is not a regular file"),
    ("../../../../../../../../etc/passwd", "must be an image file"),
    ("nowhere.pgm", "image file not found"),
])
def test_a_map_image_must_be_a_regular_image_file(tmp_path, capsys, image, problem):
    (tmp_path / "folder.pgm").mkdir()
    write_ros_map(tmp_path, image=image, pixels=254)
    path = scenario(tmp_path, world={"map": "m.yaml"})
    one_line_exit_2(capsys, path, "world.map", "image: ", problem)


def test_a_map_origin_needs_its_yaw(tmp_path, capsys):
    write_ros_map(tmp_path, origin=(0.0, 0.0), pixels=254)
    path = scenario(tmp_path, world={"map": "m.yaml"})
    one_line_exit_2(capsys, path, "origin: must be three numbers [x, y, yaw]")


def svg_scenario(tmp_path: Path, body: str, view_box: str = "0 0 600 400") -> Path:
    (tmp_path / "plan.svg").write_text(
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{view_box}">{body}</svg>')
    return scenario(tmp_path, world={"map": "plan.svg"})


@pytest.mark.parametrize("view_box, problem", [
    ("0 0 0 0", "the viewBox has no area (0 x 0"), ("0 0 600 -4", "has no area"),
    ("0 0 nan 5", "four finite numbers"), ("1 2 3", "four finite numbers"),
])
def test_an_svg_viewbox_without_area_is_refused(tmp_path, capsys, view_box, problem):
    path = svg_scenario(tmp_path, '<rect x="1" y="1" width="5" height="5"/>', view_box)
    one_line_exit_2(capsys, path, "world.map", problem)


@pytest.mark.parametrize("shape", [
    '<circle cx="300" cy="200" r="1e12" fill="none" stroke="black" stroke-width="2"/>',
    '<circle cx="300" cy="200" r="1e8" fill="none" stroke="black" stroke-width="2"/>',
    '<rect x="-1e12" y="-1e12" width="2e12" height="2e12" fill="none" stroke="black"/>',
])
def test_an_svg_shape_far_beyond_the_plan_is_refused(tmp_path, capsys, shape):
    path = svg_scenario(tmp_path, shape)
    err = one_line_exit_2(capsys, path, "world.map")
    assert "beyond the plan" in err or "points" in err


def test_an_svg_with_too_many_shapes_is_refused_before_the_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(svg, "MAX_SHAPES", 50)
    paths = "".join(f'<path d="M{2 * i} 10 l1 0 l0 1 z"/>' for i in range(60))
    path = svg_scenario(tmp_path, paths)
    one_line_exit_2(capsys, path, "more than 50 painted shapes")


def test_an_svg_file_too_large_is_refused_unread(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(svg, "MAX_FILE_BYTES", 1 << 10)
    path = svg_scenario(tmp_path, "<!--" + "x" * 2000 + '--><rect width="5" height="5"/>')
    one_line_exit_2(capsys, path, "a plan may have at most")


def test_a_long_value_is_cut_in_the_message(tmp_path, capsys):
    path = scenario(tmp_path, world={"size": [4.0, 4.0]})
    data = yaml.safe_load(path.read_text())
    data["name"] = "a" * 100_000
    path.write_text(yaml.safe_dump(data))
    err = one_line_exit_2(capsys, path, "name", "(100,002 characters)")
    assert len(err) < 400


@pytest.mark.parametrize("text, line, fragment", [
    ("name: y\nworld: {size: [4, 4]\nrobots:\n  - {name: r, pose: [1, 1, 0]}\n", 2,
     "a flow mapping is not closed"),
    ("name: y\nworld:\n  size: [4, 4\nrobots:\n  - {name: r, pose: [1, 1, 0]}\n", 3,
     "a flow sequence is not closed"),
])
def test_a_yaml_syntax_error_points_at_the_line_of_the_mistake(tmp_path, capsys, text, line,
                                                                fragment):
    path = tmp_path / "s.yaml"
    path.write_text(text)
    err = one_line_exit_2(capsys, path, fragment)
    assert err.endswith(f"(line {line})")


def test_a_long_traced_outline_builds_in_seconds_not_minutes():
    """Chipmunk's static index degrades when a wall's segments arrive in order along it (40,000
    took 4.7 s, 190,000 minutes); they are added interleaved."""
    import pymunk

    from pymunk_bot.maps.outlines import MapGeometry, add_to_space

    n = 40_000
    x = np.linspace(0.0, 60.0, n)
    y = 20.0 + 3.0 * np.sin(np.arange(n) * 0.7)
    segments = np.column_stack([x[:-1], y[:-1], x[1:], y[1:]])
    geometry = MapGeometry((), segments, np.zeros(len(segments)), (0.0, 0.0, 60.0, 40.0))
    space = pymunk.Space()
    started = time.process_time()  # CPU time: a loaded machine does not fail it
    shapes = add_to_space(space, geometry)
    assert time.process_time() - started < 2.0
    assert len(space.shapes) == len(shapes) == n - 1
    assert [tuple(s.a) for s in shapes[:3]] == [tuple(p) for p in segments[:3, :2]]  # given order
