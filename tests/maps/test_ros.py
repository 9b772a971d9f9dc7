"""ROS map_server maps: pixel rules (trinary, scale, raw, negate, alpha), layout, errors, writing."""
from __future__ import annotations

import numpy as np
import pytest
from map_helpers import turtlebot_map, write_map

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.maps.ros import read_ros_map, write_ros_map

# grey levels and what map_server makes of them with thresholds 0.65 / 0.196 (occ = 1 - v/255)
GREYS = np.array([[0, 60, 89, 90, 100, 204, 205, 206, 254, 255]], dtype=np.uint8)


def test_trinary_follows_map_server_thresholds(tmp_path):
    grid = read_ros_map(write_map(tmp_path, GREYS, occupied_thresh=0.65, free_thresh=0.196))
    # occ: 1, .765, .651, .647, .608, .2, .196, .192, .004, 0 -> occupied above .65, free below .196
    assert grid.data.tolist() == [[100, 100, 100, -1, -1, -1, -1, 0, 0, 0]]


def test_negate_swaps_black_and_white(tmp_path):
    grid = read_ros_map(write_map(tmp_path, GREYS, negate=1))
    assert grid.data.tolist() == [[0, -1, -1, -1, -1, 100, 100, 100, 100, 100]]


def test_scale_mode_interpolates_between_thresholds(tmp_path):
    grid = read_ros_map(write_map(tmp_path, np.array([[0, 128, 200, 255]], np.uint8),
                                  mode="scale", occupied_thresh=0.9, free_thresh=0.1))
    occ = 1 - np.array([128, 200]) / 255
    expected = np.rint((occ - 0.1) / 0.8 * 100).astype(int).tolist()
    assert grid.data.tolist() == [[100, *expected, 0]]


def test_scale_mode_makes_transparent_pixels_unknown_and_trinary_averages_alpha(tmp_path):
    rgba = np.zeros((1, 3, 4), np.uint8)
    rgba[0, :, :3] = 255  # white
    rgba[0, :, 3] = [255, 128, 0]  # opaque, half, transparent
    scale = read_ros_map(write_map(tmp_path, rgba, "s", "png", mode="scale"))
    assert scale.data.tolist() == [[0, -1, -1]]
    trinary = read_ros_map(write_map(tmp_path, rgba, "t", "png"))
    # shade (3 * 255 + alpha) / 4 / 255: 1.0, 0.875, 0.75 -> occ 0, .125, .25
    assert trinary.data.tolist() == [[0, 0, -1]]


def test_raw_mode_reads_values_directly(tmp_path):
    grid = read_ros_map(write_map(tmp_path, np.array([[0, 42, 100, 101, 255]], np.uint8),
                                  mode="raw", negate=1))
    assert grid.data.tolist() == [[0, 42, 100, -1, -1]]


def test_rgb_png_averages_channels(tmp_path):
    rgb = np.array([[[0, 0, 0], [255, 255, 255], [255, 0, 0]]], np.uint8)  # red: shade 1/3
    grid = read_ros_map(write_map(tmp_path, rgb, image_format="png"))
    assert grid.data.tolist() == [[100, 0, 100]]


def test_sixteen_bit_pgm(tmp_path):
    image = tmp_path / "deep.pgm"
    image.write_bytes(b"P2\n3 1\n65535\n0 65535 30000\n")
    (tmp_path / "deep.yaml").write_text("image: deep.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n")
    assert read_ros_map(tmp_path / "deep.yaml").data.tolist() == [[100, 0, -1]]


def test_rows_are_flipped_and_origin_is_the_lower_left_corner(tmp_path):
    pixels = np.full((4, 3), 254, np.uint8)
    pixels[0, 2] = 0  # top right pixel of the image
    grid = read_ros_map(write_map(tmp_path, pixels, origin="[-1.0, 2.0, 0.0]", resolution=0.5))
    assert grid.origin == (-1.0, 2.0) and grid.resolution == 0.5
    assert grid.data[3, 2] == 100 and grid.data.sum() == 100
    row, col = grid.cell_of(np.array([0.25 + 0.01, 2.0 + 1.75]))  # top right cell's area
    assert (row, col) == (3, 2)


def test_image_path_is_relative_to_the_yaml(tmp_path, monkeypatch):
    sub = tmp_path / "maps"
    sub.mkdir()
    yaml_path = write_map(sub, turtlebot_map(64))
    monkeypatch.chdir(tmp_path)
    assert read_ros_map("maps/map.yaml").data.shape == (64, 64)
    assert yaml_path.exists()


@pytest.mark.parametrize("keys, extra, message", [
    ({"occupied_thresh": 1.5}, "", "occupied_thresh: must be in [0, 1] (got 1.5)"),
    ({"free_thresh": 0.7}, "", "free_thresh: must be below occupied_thresh (0.65) (got 0.7)"),
    ({"mode": "fancy"}, "", "mode: must be one of trinary, scale, raw (got 'fancy')"),
    ({"origin": "[0, 0, 0.5]"}, "", "origin[2]: a rotated map is not supported"),
    ({"resolution": -1}, "", "resolution: must be > 0"),
    ({"negate": 2}, "", "negate: must be 0 or 1 (got 2)"),
    ({}, "occupied_tresh: 0.6\n", "occupied_tresh: unknown key (did you mean 'occupied_thresh'?)"),
    ({"image": "nothere.pgm"}, "", "image: image file not found"),
    ({"resolution": ".nan"}, "", "resolution: must be finite"),
])
def test_bad_map_yaml_is_one_line_naming_scenario_and_key(tmp_path, keys, extra, message):
    yaml_path = write_map(tmp_path, GREYS, extra=extra, **keys)
    with pytest.raises(ScenarioError) as info:
        read_ros_map(yaml_path, source="scen.yaml", key_path="world.map")
    text = str(info.value)
    assert text.startswith(f"scen.yaml: world.map: {yaml_path}: ") and message in text
    assert "\n" not in text


def test_missing_key_missing_file_bad_image_and_yaml_syntax(tmp_path):
    with pytest.raises(ScenarioError, match="map file not found"):
        read_ros_map(tmp_path / "none.yaml")
    (tmp_path / "a.yaml").write_text("image: a.pgm\norigin: [0, 0, 0]\n")
    with pytest.raises(ScenarioError, match="resolution: required key is missing"):
        read_ros_map(tmp_path / "a.yaml")
    (tmp_path / "b.pgm").write_bytes(b"not an image at all")
    (tmp_path / "b.yaml").write_text("image: b.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    with pytest.raises(ScenarioError, match="image: cannot read b.pgm as an image"):
        read_ros_map(tmp_path / "b.yaml")
    (tmp_path / "c.yaml").write_text("image: [unclosed\n")
    with pytest.raises(ScenarioError, match="YAML syntax error"):
        read_ros_map(tmp_path / "c.yaml")


def test_absurd_image_size_is_refused_before_decoding(tmp_path):
    image = tmp_path / "huge.pgm"
    (tmp_path / "huge.yaml").write_text("image: huge.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    for side, message in ((30000, "more than 64,000,000 pixels"),
                          (12000, "12000 x 12000 pixels; at most 20000 per side")):
        image.write_bytes(f"P5\n{side} {side}\n255\n".encode())  # header only: never decoded
        with pytest.raises(ScenarioError, match=message):
            read_ros_map(tmp_path / "huge.yaml")


def test_written_map_reads_back_cell_for_cell(tmp_path):
    rng = np.random.default_rng(4)
    data = rng.choice(np.array([-1, 0, 100], np.int8), size=(37, 51))
    grid = OccupancyGrid(data, 0.1, (-2.5, 3.0))
    image = write_ros_map(grid, tmp_path / "out.yaml")
    assert image == tmp_path / "out.pgm" and image.read_bytes().startswith(b"P5\n51 37\n255\n")
    back = read_ros_map(tmp_path / "out.yaml")
    assert np.array_equal(back.data, data)
    assert back.origin == (-2.5, 3.0) and back.resolution == 0.1
