"""`pymunk-bot run SCENARIO --map-out OUT.yaml`: the built map saved as a ROS map."""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from pymunk_bot.cli import main
from pymunk_bot.config import load_scenario
from pymunk_bot.localization.metrics import map_scores
from pymunk_bot.maps.rasterize import scenario_grid
from pymunk_bot.maps.ros import read_ros_map

ROBOT = {"lidar": {"beams": 180, "max_range": 6.0, "noise_std": 0.01, "rate": 10.0},
         "controller": {"type": "velocity", "v": 0.0, "omega": 0.8}}
ROOM = {"name": "mapped_room", "seed": 3, "world": {"size": [4.0, 3.0], "duration": 2.0},
        "obstacles": [{"type": "box", "center": [2.8, 1.5], "size": [0.4, 0.4]},
                      {"type": "wall", "start": [0.0, 2.2], "end": [1.5, 2.2], "thickness": 0.05}],
        "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0], **ROBOT},
                   {"name": "r2", "pose": [3.3, 0.6, 0.0], "mapping": {"resolution": 0.05},
                    **ROBOT},
                   {"name": "r3", "pose": [1.0, 2.6, 0.0], "mapping": {"resolution": 0.1},
                    **ROBOT}]}


@pytest.fixture
def room(tmp_path):
    path = tmp_path / "room.yaml"
    path.write_text(yaml.safe_dump(ROOM))
    return path


def _run(room, *extra: str) -> int:
    return main(["run", str(room), "--headless", *extra])


def test_the_written_map_reads_back_and_matches_the_true_geometry(room, tmp_path, capsys):
    out = tmp_path / "maps" / "built.yaml"
    out.parent.mkdir()
    assert _run(room, "--map-out", str(out)) == 0
    assert "r2's map" in capsys.readouterr().out  # the first robot that maps
    assert (tmp_path / "maps" / "built.pgm").is_file()
    grid = read_ros_map(out)
    assert grid.resolution == pytest.approx(0.05)
    truth = scenario_grid(load_scenario(str(room)), 0.05)
    scores = map_scores(grid, truth)
    assert scores["precision"] >= 0.95
    assert scores["recall"] >= 0.8
    # the face of the box r2 sees is occupied, the robot's own spot as free
    for (x, y), occupied in (((2.98, 1.5), True), ((3.3, 0.6), False)):
        r, c = grid.cell_of(np.array([x, y]))
        assert (grid.data[r, c] == 100) == occupied


def test_map_robot_picks_the_robot(room, tmp_path, capsys):
    out = tmp_path / "r3.yaml"
    assert _run(room, "--map-out", str(out), "--map-robot", "r3") == 0
    assert "r3's map" in capsys.readouterr().out
    assert read_ros_map(out).resolution == pytest.approx(0.1)


@pytest.mark.parametrize("extra, message", [
    (("--map-out", "{tmp}/none/m.yaml"), "--map-out: {tmp}/none/m.yaml: directory {tmp}/none does not exist"),
    (("--map-out", "{tmp}/m.png"), "--map-out: {tmp}/m.png: unsupported file type ('.png')"),
    (("--map-out", "{tmp}/m.yaml", "--map-robot", "bob"), "--map-robot: no robot named 'bob'"),
    (("--map-out", "{tmp}/m.yaml", "--map-robot", "r1"), "--map-robot: robot 'r1' builds no map"),
    (("--map-robot", "r2"), "--map-robot: only applies with --map-out"),
])
def test_bad_map_options_fail_before_the_run_with_one_line(room, tmp_path, capsys, extra, message):
    args = [a.format(tmp=tmp_path) for a in extra]
    assert _run(room, "--duration", "1000", *args) == 2  # checked first: no 1000 s run
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message.format(tmp=tmp_path) in err
    assert not list(tmp_path.glob("m.*"))


def test_a_scenario_without_a_mapping_robot_is_refused(tmp_path, capsys):
    path = tmp_path / "plain.yaml"
    plain = {**ROOM, "robots": [ROOM["robots"][0]]}
    path.write_text(yaml.safe_dump(plain))
    assert _run(path, "--duration", "1000", "--map-out", str(tmp_path / "m.yaml")) == 2
    assert "no robot builds a map" in capsys.readouterr().err
