"""`world.map` in the core: a ROS map is the arena (walls, LiDAR, contacts, start checks, planning,
logs and the `map` command all see it)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from map_helpers import write_map

from pymunk_bot import Simulation
from pymunk_bot.cli import main
from pymunk_bot.config import load_scenario, parse_scenario
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.maps.files import load_world_map
from pymunk_bot.maps.rasterize import scenario_grid
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.map import MapInfo
from command import pymunk_bot

REPO = Path(__file__).resolve().parents[2]
RES = 0.05  # [m] per cell of the test map
ORIGIN = (-1.0, -0.5)  # [m]
FREE_BOX = (-0.55, -0.05, 4.55, 3.05)  # [m] the room inside the wall ring: x0, y0, x1, y1
PILLAR = (1.5, 1.5, 2.0, 2.0)  # [m] an occupied square in the room


def room_pixels() -> np.ndarray:
    """120 x 80 cells (top row first): unknown border, 4-cell wall ring, a room, a pillar."""
    pixels = np.full((80, 120), 205, dtype=np.uint8)
    pixels[5:75, 5:115] = 0
    pixels[9:71, 9:111] = 254
    pixels[30:40, 50:60] = 0  # grid rows 40..49 (bottom first), columns 50..59
    return pixels


def room_scenario(tmp_path: Path, pose=(0.5, 0.5, 0.0), **robot_keys) -> Path:
    """A scenario file beside maps/room.yaml (the map referenced by a relative path)."""
    (tmp_path / "maps").mkdir(exist_ok=True)
    write_map(tmp_path / "maps", room_pixels(), name="room", origin=f"[{ORIGIN[0]}, {ORIGIN[1]}, 0.0]")
    data = {"name": "room", "world": {"map": "maps/room.yaml", "duration": 3.0},
            "robots": [{"name": "r1", "pose": list(pose), **robot_keys}]}
    path = tmp_path / "room.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_a_ros_map_is_the_arena_relative_to_the_scenario_file(tmp_path, monkeypatch):
    path = room_scenario(tmp_path)
    monkeypatch.chdir(REPO)  # elsewhere: the map path is relative to the scenario file
    sim = Simulation.from_file(str(path))
    assert sim.world.extent == pytest.approx((-1.0, -0.5, 5.0, 3.5))
    assert (sim.world.width, sim.world.height) == pytest.approx((6.0, 4.0))
    assert sim.config.world.size == pytest.approx((6.0, 4.0))
    # The map's shapes instead of the four 1 m arena walls: the room ring and the pillar.
    assert len(sim.world.arena_shapes) >= 5 and all(
        s.body is sim.world.space.static_body for s in sim.world.arena_shapes)
    sim.run(1.0)
    assert sim.time == pytest.approx(1.0)
    # Loaded once: parsing the scenario again reuses the traced geometry.
    again = load_scenario(str(path))
    assert again.world.map_geometry() is sim.config.world.map_geometry()


def test_a_robot_driving_into_a_map_wall_stops_at_it(tmp_path):
    path = room_scenario(tmp_path, pose=(3.5, 1.0, 0.0), controller={"type": "velocity", "v": 1.0})
    sim = Simulation.from_file(str(path))
    robot = sim.robots["r1"]
    deepest = []
    sim.observers.append(lambda s: deepest.append(robot.pose[0] + robot.radius - FREE_BOX[2]))
    sim.run(2.0)
    assert robot.collisions == 1  # one contact episode, no chatter along the segment chain
    assert max(deepest) <= 0.01  # penetration into the wall [m]
    assert robot.pose[0] == pytest.approx(FREE_BOX[2] - robot.radius, abs=0.01)
    assert abs(robot.velocity[0]) < 1e-6  # stopped, not bouncing


def _ray_box_exit(origin, direction, box) -> float:
    """Distance from a point inside an axis-aligned box to its boundary along ``direction``."""
    best = math.inf
    for axis in (0, 1):
        d = direction[axis]
        if abs(d) > 1e-12:
            wall = box[axis + 2] if d > 0 else box[axis]
            best = min(best, (wall - origin[axis]) / d)
    return best


def _ray_box_entry(origin, direction, box) -> float:
    """Distance to where the ray enters a box from outside (inf if it misses)."""
    t0, t1 = 0.0, math.inf
    for axis in (0, 1):
        d, o = direction[axis], origin[axis]
        lo, hi = box[axis], box[axis + 2]
        if abs(d) < 1e-12:
            if not lo <= o <= hi:
                return math.inf
            continue
        a, b = sorted(((lo - o) / d, (hi - o) / d))
        t0, t1 = max(t0, a), min(t1, b)
    return t0 if t0 <= t1 else math.inf


def test_lidar_on_a_map_reads_the_map_within_a_cell(tmp_path):
    path = room_scenario(tmp_path, pose=(0.7, 0.9, 0.3),
                         lidar={"beams": 360, "max_range": 10.0, "min_range": 0.0})
    sim = Simulation.from_file(str(path))
    robot = sim.robots["r1"]
    ranges = robot.lidar.scan()
    x, y, theta = robot.pose
    expected = []
    for angle in robot.lidar.angles + theta:
        direction = (math.cos(angle), math.sin(angle))
        expected.append(min(_ray_box_exit((x, y), direction, FREE_BOX),
                            _ray_box_entry((x, y), direction, PILLAR)))
    error = np.abs(ranges - np.array(expected))
    assert error.max() <= RES
    assert np.median(error) < 1e-6  # the outline runs along the cell edges


@pytest.mark.parametrize("pose, what", [((-0.65, 1.0, 0.0), "occupied"),
                                        ((-0.9, 1.0, 0.0), "unknown"),
                                        ((1.75, 1.75, 0.0), "occupied")])
def test_a_robot_starting_on_a_solid_cell_is_refused(tmp_path, pose, what):
    path = room_scenario(tmp_path, pose=pose, radius=0.05)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(str(path))
    message = str(caught.value)
    assert "robots[0].pose" in message and "world.map" in message and what in message
    assert "\n" not in message


def test_cli_reports_a_start_in_a_wall_in_one_line_with_exit_2(tmp_path):
    path = room_scenario(tmp_path, pose=(-0.65, 1.0, 0.0))
    done = pymunk_bot("validate", path, cwd=REPO)
    assert done.returncode == 2
    line = done.stderr.strip()
    assert line.startswith("error: ") and "\n" not in line
    assert "robots[0].pose" in line and "world.map" in line


def _room_data(tmp_path: Path, **world) -> dict:
    room_scenario(tmp_path)
    data = yaml.safe_load((tmp_path / "room.yaml").read_text())
    data["world"].update(world)
    return data


@pytest.mark.parametrize("world, key, words", [
    ({"size": [6.0, 4.0]}, "world.size", "not both"),
    ({"map_scale": 0.01}, "world.map_scale", "SVG"),
    ({"map": "maps/nowhere.yaml"}, "world.map", "not found"),
    ({"map": "maps/room.png"}, "world.map", "unknown map format"),
    ({"map": None}, "world.size", "required"),
])
def test_bad_map_keys_are_one_line_errors(tmp_path, world, key, words):
    data = _room_data(tmp_path, **world)
    if world.get("map", "") is None:
        del data["world"]["map"]
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(data, str(tmp_path / "room.yaml"))
    assert caught.value.path == key and words in str(caught.value)


def test_goals_and_waypoints_must_be_in_free_space(tmp_path):
    data = _room_data(tmp_path)
    source = str(tmp_path / "room.yaml")
    data["robots"][0]["goal"] = {"position": [1.75, 1.75]}  # on the pillar
    with pytest.raises(ScenarioError, match="occupied cell of world.map") as caught:
        parse_scenario(data, source)
    assert caught.value.path == "robots[0].goal.position"
    data["robots"][0]["goal"] = {"position": [6.0, 1.0]}  # beyond the extent
    with pytest.raises(ScenarioError, match="extent"):
        parse_scenario(data, source)
    del data["robots"][0]["goal"]
    data["robots"][0]["controller"] = {"type": "waypoints", "points": [[1.0, 1.0], [-0.9, 1.0]]}
    with pytest.raises(ScenarioError, match="unknown cell") as caught:
        parse_scenario(data, source)
    assert caught.value.path == "robots[0].controller.points[1]"


def test_from_dict_resolves_the_map_against_the_current_directory(tmp_path, monkeypatch):
    data = _room_data(tmp_path)
    monkeypatch.chdir(tmp_path)
    sim = Simulation.from_dict(data)
    assert sim.world.extent == pytest.approx((-1.0, -0.5, 5.0, 3.5))
    monkeypatch.chdir(REPO)
    with pytest.raises(ScenarioError, match="world.map"):
        Simulation.from_dict(data)


def test_planning_and_localizer_maps_hold_the_map(tmp_path):
    config = load_scenario(str(room_scenario(tmp_path)))
    info = MapInfo.from_scenario(config)
    assert info.origin == pytest.approx(ORIGIN) and info.size == pytest.approx((6.0, 4.0))
    grid = ClearanceGrid.from_map(info, 0.05, cap=1.0)
    assert grid.clearance[grid.cell_of(1.75, 1.75)] == 0.0  # inside the pillar
    assert grid.clearance[grid.cell_of(1.0, 1.75)] == pytest.approx(0.475, abs=0.03)
    assert grid.clearance[grid.cell_of(-0.3, 1.0)] == pytest.approx(0.225, abs=0.03)
    own = config.world.map_geometry().grid
    assert scenario_grid(config, RES) is own  # a ROS map at its own resolution: itself
    coarse = scenario_grid(config, 0.1)
    row, col = coarse.cell_of(np.array([[-0.9, 1.0], [1.75, 1.75], [1.0, 1.0]]))
    assert coarse.data[row, col].tolist() == [100, 100, 0]  # unknown counts as solid


def test_navigate_crosses_the_office_map():
    from pymunk_bot.maps.outlines import free_disc

    sim = Simulation.from_file("floor_plan")
    robot = sim.robots["r1"]
    geometry = sim.config.world.map_geometry()
    sim.step()
    path = np.asarray(robot.controller.debug_path())
    # The straight line crosses room walls; the plan keeps the robot clear of every wall.
    start, goal = robot.pose[:2], np.asarray(robot.goal)
    line = start + np.linspace(0, 1, 200)[:, None] * (goal - start)
    assert not all(free_disc(geometry, x, y, robot.radius) for x, y in line)
    assert len(path) > 2 and all(free_disc(geometry, x, y, robot.radius) for x, y in path)
    sim.run(sim.config.world.duration - sim.time)
    assert robot.goal_reached and robot.collisions == 0
    assert sim.result()["passed"]


def test_map_command_round_trips_a_map_scenario(tmp_path):
    path = room_scenario(tmp_path)
    out = tmp_path / "again.yaml"
    assert main(["map", str(path), "-o", str(out)]) == 0
    first = load_world_map(tmp_path / "maps" / "room.yaml").grid
    again = load_world_map(out).grid
    assert again.origin == pytest.approx(first.origin) and again.resolution == first.resolution
    assert np.array_equal(again.data, first.data)


def _grid_of(mask: np.ndarray):
    from pymunk_bot.maps.grid import OccupancyGrid
    return OccupancyGrid(np.where(mask, 100, 0).astype(np.int8), RES)


def test_a_rasterised_rotated_box_is_one_shape_and_a_diagonal_wall_has_no_gap():
    import pymunk

    from pymunk_bot.maps.outlines import add_to_space, geometry_from_grid

    yy, xx = (np.mgrid[:120, :120] + 0.5) * RES
    u = (xx - 3.0) * math.cos(0.4) + (yy - 3.0) * math.sin(0.4)
    v = -(xx - 3.0) * math.sin(0.4) + (yy - 3.0) * math.cos(0.4)
    box = (np.abs(u) <= 1.0) & (np.abs(v) <= 0.5)
    assert len(geometry_from_grid(_grid_of(box)).polygons) == 1  # not a staircase of pieces
    wall = np.zeros((120, 120), dtype=bool)
    k = np.arange(10, 110)
    wall[k, k] = True  # one cell thick, cells touching only at their corners
    space = pymunk.Space()
    add_to_space(space, geometry_from_grid(_grid_of(wall)))
    for t in np.linspace(0.6, 5.3, 95):  # rays across the wall between every pair of cells
        hit = space.segment_query_first((t + 0.4, t - 0.4), (t - 0.4, t + 0.4), 0.0,
                                        pymunk.ShapeFilter())
        assert hit is not None
