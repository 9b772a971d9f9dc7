"""`pymunk-bot map` round trip and `pymunk-bot generate`: same LiDAR, deterministic, solvable."""
from __future__ import annotations

import numpy as np
import pymunk
import pytest
import yaml

from pymunk_bot import Simulation
from pymunk_bot.cli import main
from pymunk_bot.config import load_scenario
from pymunk_bot.maps.files import load_world_map
from pymunk_bot.maps.generate import KINDS, solution_length
from pymunk_bot.maps.outlines import add_to_space
from pymunk_bot.sensors.raycast import RayCaster

STATIC_WORLD = {
    "name": "static", "world": {"size": [8.0, 5.0]},
    "obstacles": [
        {"type": "box", "center": [2.0, 1.0], "size": [0.8, 0.5], "angle": 0.3},
        {"type": "circle", "center": [6.0, 3.5], "radius": 0.4},
        {"type": "polygon", "points": [[4, 0.5], [5, 0.5], [5, 1.5], [4.5, 1.0], [4, 1.5]]},
        {"type": "wall", "start": [3.0, 3.0], "end": [3.0, 5.0], "thickness": 0.1},
    ],
    "robots": [{"name": "r1", "pose": [4.0, 2.6, 0.4],
                "lidar": {"beams": 360, "max_range": 10.0, "min_range": 0.0}}],
}


def _nearest_surface(space: pymunk.Space, points: np.ndarray) -> np.ndarray:
    return np.array([abs(space.point_query_nearest(tuple(p), 5.0, pymunk.ShapeFilter()).distance)
                     for p in points])


@pytest.mark.parametrize("resolution", [0.05, 0.02])
def test_written_map_gives_the_same_lidar_within_a_cell(tmp_path, resolution):
    scenario = tmp_path / "static.yaml"
    scenario.write_text(yaml.safe_dump(STATIC_WORLD))
    out = tmp_path / "static_map.yaml"
    assert main(["map", str(scenario), "-o", str(out), "--resolution", str(resolution)]) == 0
    assert (tmp_path / "static_map.pgm").read_bytes().startswith(b"P5\n")
    geometry = load_world_map(out)
    space = pymunk.Space()
    add_to_space(space, geometry)
    sim = Simulation.from_file(str(scenario))
    robot = sim.robots["r1"]
    truth = robot.lidar.scan()
    x, y, theta = robot.pose
    angles = robot.lidar.angles + theta
    ranges = RayCaster(space).cast((x, y), angles, 10.0)
    assert np.all(ranges < 10.0) and np.all(truth < 10.0)  # closed on both sides
    # Each map hit lies within a cell of the scenario's surfaces, and each true hit within a
    # cell of the map's; ranges agree within a cell except for beams grazing a surface.
    rays = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    tolerance = resolution * 1.2
    assert _nearest_surface(sim.world.space, (x, y) + ranges[:, None] * rays).max() < tolerance
    assert _nearest_surface(space, (x, y) + truth[:, None] * rays).max() < tolerance
    # Straightened outlines lie about a cell outside a surface the writer rasterised (a cell
    # is occupied within half a cell of it), so some ranges are short by a hair over a cell.
    assert np.mean(np.abs(ranges - truth) <= resolution) > 0.85
    assert np.mean(np.abs(ranges - truth) <= tolerance) > 0.92


def test_map_command_bad_input_exits_2(tmp_path, capsys):
    assert main(["map", "scenarios/maze.yaml", "-o", str(tmp_path / "m.png")]) == 2
    assert main(["map", "scenarios/maze.yaml", "-o", str(tmp_path / "m.yaml"),
                 "--resolution", "0"]) == 2
    assert main(["map", "scenarios/maze.yaml", "-o", str(tmp_path / "no/dir/m.yaml")]) == 2
    assert main(["map", str(tmp_path / "missing.yaml"), "-o", str(tmp_path / "m.yaml")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 4 and all(line.startswith("error: ") for line in lines)


@pytest.mark.parametrize("kind", KINDS)
def test_generated_worlds_are_deterministic_valid_and_solvable(tmp_path, kind):
    a, b, c = (tmp_path / f"{n}.yaml" for n in "abc")
    assert main(["generate", kind, "--seed", "5", "-o", str(a)]) == 0
    assert main(["generate", kind, "--seed", "5", "-o", str(b)]) == 0
    assert main(["generate", kind, "--seed", "6", "-o", str(c), "--size", "10", "7"]) == 0
    assert a.read_bytes() == b.read_bytes() and a.read_bytes() != c.read_bytes()
    for path in (a, c):
        config = load_scenario(str(path))
        length = solution_length(config)
        assert length is not None and length > 3.0
        assert config.expect["r1"].goal_reached and config.expect["r1"].max_collisions == 0


def test_generated_office_is_driven_to_its_goal(tmp_path):
    out = tmp_path / "office.yaml"
    assert main(["generate", "office", "--seed", "2", "-o", str(out), "--size", "10", "7"]) == 0
    sim = Simulation.from_file(str(out))
    sim.run(sim.config.expect["r1"].within)
    result = sim.result()
    assert result["robots"]["r1"]["goal_reached"] and result["robots"]["r1"]["collisions"] == 0


def test_generate_bad_input_exits_2(tmp_path, capsys):
    assert main(["generate", "maze", "-o", str(tmp_path / "w.yaml"), "--size", "1", "5"]) == 2
    assert main(["generate", "maze", "-o", str(tmp_path / "w.yaml"), "--seed", "-3"]) == 2
    assert "--size: each side must be between 4 and 100 m" in capsys.readouterr().err
