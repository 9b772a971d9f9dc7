"""Defects 4 and 5 of issue 20: `localization: slam` without `mapping`, and ROS map origins.

The map here is a 4 x 3 m room drawn as a ROS map whose ``origin`` is [-10, -10, 0] (as most
ROS maps have a negative origin): the arena spans [-10, -6] x [-10, -7].
"""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from pymunk_bot import Simulation
from pymunk_bot.cli import main
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.maps.ros import write_ros_map

ORIGIN = (-10.0, -10.0)  # [m]
RES = 0.05  # [m]
LIDAR = {"beams": 180, "max_range": 6.0, "noise_std": 0.01, "rate": 10.0}


def _room_grid() -> OccupancyGrid:
    rows, cols = int(3.0 / RES), int(4.0 / RES)
    data = np.zeros((rows, cols), dtype=np.int8)
    data[:3, :] = data[-3:, :] = 100  # 15 cm thick outer walls
    data[:, :3] = data[:, -3:] = 100
    data[int(1.2 / RES):int(1.8 / RES), int(2.6 / RES):int(3.0 / RES)] = 100  # a box
    return OccupancyGrid(data, RES, ORIGIN)


@pytest.fixture
def room_map(tmp_path):
    out = tmp_path / "room.yaml"
    write_ros_map(_room_grid(), out)
    text = yaml.safe_load(out.read_text())
    assert text["origin"][:2] == list(ORIGIN)
    return out


def _scenario(room_map, localization, controller, duration=2.0) -> dict:
    return {"name": "negative_origin", "seed": 1,
            "world": {"map": str(room_map), "duration": duration},
            "robots": [{"name": "r1", "pose": [-9.3, -9.3, 0.0], "lidar": LIDAR,
                        "localization": localization, "controller": controller}]}


def test_a_waypoint_inside_a_map_with_a_negative_origin_is_accepted(room_map, tmp_path, capsys):
    data = _scenario(room_map, "odometry",
                     {"type": "waypoints", "points": [[-8.0, -9.3], [-8.0, -7.8]]})
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["validate", str(path)]) == 0, capsys.readouterr()
    outside = _scenario(room_map, "odometry", {"type": "waypoints", "points": [[-5.0, -9.3]]})
    path.write_text(yaml.safe_dump(outside))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "points[0]" in err and "[-10, -6]" in err  # the arena named in the map's frame


def test_slam_without_a_mapping_key_runs_and_maps_in_the_maps_frame(room_map):
    sim = Simulation.from_dict(_scenario(room_map, "slam",
                                         {"type": "velocity", "v": 0.0, "omega": 0.6}))
    sim.run(2.0)  # crashed: 'SlamLocalizer' object has no attribute 'due'
    robot = sim.robots["r1"]
    assert robot.localizer.context.origin == ORIGIN
    grid = robot.mapper.grid
    assert grid.origin[0] <= ORIGIN[0] and grid.origin[1] <= ORIGIN[1]
    # The walls it saw landed on the map's walls: the west wall's face (x = -9.85) is occupied
    # where the robot saw it, the robot's own cell is free.
    def value(x, y):
        col = int((x - grid.origin[0]) / grid.resolution)
        row = int((y - grid.origin[1]) / grid.resolution)
        return int(grid.data[row, col])
    assert max(value(x, -9.3) for x in (-9.88, -9.83)) > 65
    assert 0 <= value(-9.3, -9.3) < 20
    assert np.hypot(*(robot.localizer.pose[:2] - robot.pose[:2])) < 0.05


def test_the_plot_of_a_map_world_shows_its_walls_at_the_maps_coordinates(room_map):
    pytest.importorskip("matplotlib")
    from pymunk_bot.viewer.plots import make_figure
    from pymunk_bot.outcomes.runlog import RunLogger

    sim = Simulation.from_dict(_scenario(room_map, "odometry",
                                         {"type": "velocity", "v": 0.2, "omega": 0.0}))
    logger = RunLogger().attach(sim)
    sim.run(1.0)
    fig = make_figure(logger.log(), "map")
    ax = fig.axes[0]
    assert ax.get_xlim() == pytest.approx((-10.0, -6.0))
    assert ax.get_ylim() == pytest.approx((-10.0, -7.0))
    # The floor is drawn inside the map's extent, and the map's box (its shapes were skipped
    # as "walls") over it in the wall colour.
    from pymunk_bot.viewer import palette as pal
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    image = np.asarray(canvas.buffer_rgba())[..., :3].astype(int)
    height = image.shape[0]

    def pixel(x, y):
        px, py = ax.transData.transform((x, y))
        return image[int(round(height - py)), int(round(px))]
    assert np.abs(pixel(-8.0, -7.4) - np.array(pal.FLOOR)[:3]).max() < 10
    assert np.abs(pixel(-7.2, -8.5) - np.array(pal.WALL)[:3]).max() < 10


def _validate(tmp_path, data) -> tuple[int, str]:
    import contextlib
    import io

    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(["validate", str(path)])
    return code, err.getvalue()


def test_scripted_paths_and_pedestrians_are_checked_in_the_maps_frame(room_map, tmp_path):
    data = _scenario(room_map, "odometry", {"type": "velocity", "v": 0.0, "omega": 0.0})
    data["obstacles"] = [
        {"type": "box", "center": [-8.0, -8.0], "size": [0.3, 0.3],
         "motion": {"path": [[-8.0, -8.0], [-7.0, -8.0]], "speed": 0.3}},
        {"type": "pedestrian", "center": [-9.0, -7.6], "goals": [[-7.0, -7.6]]}]
    assert _validate(tmp_path, data) == (0, "")  # refused as outside [0, 4] x [0, 3] before
    data["obstacles"][0]["motion"]["path"][1] = [-5.0, -8.0]  # beyond x = -6
    code, err = _validate(tmp_path, data)
    assert code == 2 and "obstacles[0].motion.path[1]" in err and "[-10, -6] x [-10, -7]" in err
    data["obstacles"] = [{"type": "pedestrian", "center": [-9.0, -7.6], "goals": [[-5.5, -7.6]]}]
    code, err = _validate(tmp_path, data)
    assert code == 2 and "obstacles[0].goals[0]" in err and "[-10, -6] x [-10, -7]" in err


def test_the_viewer_shows_a_map_with_a_negative_origin_and_takes_goals_on_it(room_map):
    pytest.importorskip("pygame")
    import os

    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    import pygame

    from pymunk_bot.viewer import palette as pal
    from pymunk_bot.viewer.app import Viewer
    from pymunk_bot.viewer.sources import LiveSource

    sim = Simulation.from_dict(_scenario(room_map, "odometry",
                                         {"type": "waypoints", "points": [[-8.0, -9.3]]}))
    surface = pygame.Surface((400, 300))
    viewer = Viewer(LiveSource(sim), (400, 300))
    viewer.layers.grid = False
    viewer.draw(surface, hud=False)
    # the whole map is in view: its corners land inside the window
    for corner in ((-10.0, -10.0), (-6.0, -7.0)):
        px, py = viewer.camera.to_screen(*corner)
        assert 0 <= px <= 400 and 0 <= py <= 300
    # the floor where the map is free, the wall colour on the map's box
    def colour(x, y):
        px, py = viewer.camera.to_screen(x, y)
        return np.array(tuple(surface.get_at((int(px), int(py))))[:3])
    assert np.abs(colour(-8.0, -7.6) - np.array(pal.FLOOR)[:3]).max() < 10
    assert np.abs(colour(-7.2, -8.5) - np.array(pal.WALL)[:3]).max() < 10  # the map's box
    assert np.abs(colour(-10.2, -8.5) - np.array(pal.BACKGROUND)[:3]).max() < 10  # off the map
    # a click on the map sends the robot there (it was refused as outside [0, w] x [0, h])
    viewer.selected = "r1"
    viewer.click(*viewer.camera.to_screen(-7.0, -8.0))
    assert sim.robots["r1"].nav_goal == pytest.approx((-7.0, -8.0), abs=0.05)


def test_pymunk_bot_map_keeps_the_maps_origin(room_map, tmp_path, capsys):
    data = _scenario(room_map, "odometry", {"type": "velocity", "v": 0.0, "omega": 0.0})
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text(yaml.safe_dump(data))
    out = tmp_path / "out.yaml"
    assert main(["map", str(scenario), "-o", str(out), "--resolution", "0.05"]) == 0
    meta = yaml.safe_load(out.read_text())
    assert -10.5 <= meta["origin"][0] <= -10.0 and -10.5 <= meta["origin"][1] <= -10.0
    from pymunk_bot.maps.ros import read_ros_map

    grid = read_ros_map(out)
    def occupied(x, y):
        col = int((x - grid.origin[0]) / grid.resolution)
        row = int((y - grid.origin[1]) / grid.resolution)
        return grid.data[row, col] >= 65
    assert occupied(-9.95, -8.5) and occupied(-7.2, -8.5)  # the west wall, the box
    assert not occupied(-8.0, -8.0) and not occupied(-9.3, -9.3)
