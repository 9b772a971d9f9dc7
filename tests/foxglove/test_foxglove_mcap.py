"""`run --log run.mcap`: Foxglove schemas, readable by the `mcap` library, equal to the truth."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from builders import robot, scenario, wheels
from foxglove_helpers import read_mcap

from pymunk_bot import Simulation
from pymunk_bot.foxglove.frames import quaternion_yaw
from pymunk_bot.foxglove.mcap_log import McapLogger
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.outcomes.runlog import RunLogger


def lidar_sim(**lidar):
    lidar = {"beams": 90, "max_range": 4.0, "rate": 10.0, "noise_std": 0.01,
             "offset": [0.1, 0.0, 0.5], **lidar}
    return Simulation.from_dict(scenario(
        [robot([1.0, 1.5, 0.0], name="r1", controller=wheels(0.5, 0.6), lidar=lidar),
         robot([3.0, 0.6, 1.0], name="r2")],
        [{"type": "box", "center": [2.5, 3.0], "size": [0.4, 0.4], "movable": True},
         {"type": "circle", "center": [4.0, 2.0], "radius": 0.3}], size=(6.0, 4.0)), seed=3)


def pose_xyt(msg):
    p, q = msg.pose.position, msg.pose.orientation
    return np.array([p.x, p.y, quaternion_yaw(q.x, q.y, q.z, q.w)])


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """One 2 s run logged to .npz and .mcap at once, read back."""
    path = tmp_path_factory.mktemp("mcap") / "run.mcap"
    sim = lidar_sim()
    npz = RunLogger().attach(sim)
    mcap = McapLogger(path).attach(sim)
    sim.run(2.0)
    mcap.save()
    summary, messages = read_mcap(path)
    return SimpleNamespace(sim=sim, log=npz.log(), summary=summary, messages=messages, path=path)


def test_channels_carry_foxglove_schemas(recorded):
    summary = recorded.summary
    schemas = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    assert schemas == {
        "/tf": "foxglove.FrameTransforms", "/scene": "foxglove.SceneUpdate",
        "/r1/ground_truth": "foxglove.PoseInFrame", "/r1/odometry": "foxglove.PoseInFrame",
        "/r2/ground_truth": "foxglove.PoseInFrame", "/r2/odometry": "foxglove.PoseInFrame",
        "/r1/scan": "foxglove.LaserScan", "/r1/state": "pymunk_bot.RobotState",
        "/r2/state": "pymunk_bot.RobotState", "/obstacles/poses": "pymunk_bot.ObstaclePoses"}
    counts = {summary.channels[c].topic: n
              for c, n in summary.statistics.channel_message_counts.items()}
    steps = 121  # the start and 120 steps of 1/60 s
    assert counts["/tf"] == counts["/r1/ground_truth"] == counts["/r2/state"] == steps
    assert counts["/r1/scan"] == len(recorded.log.scans["r1"].time) == 21  # 10 Hz, t = 0..2 s
    # chunked and compressed
    assert summary.chunk_indexes and {c.compression for c in summary.chunk_indexes} == {"zstd"}
    assert not [p for p in recorded.path.parent.iterdir() if p.name.endswith(".tmp")]


def test_scans_equal_the_npz_log_and_the_sensor_geometry(recorded):
    scans = recorded.messages["/r1/scan"]
    logged = recorded.log.scans["r1"]
    lidar = recorded.sim.robots["r1"].lidar
    for k, (log_time, _, scan) in enumerate(scans):
        assert np.array_equal(np.array(scan.ranges, dtype=np.float32), logged.ranges[k])
        assert log_time == round(logged.time[k] * 1e9)
        assert scan.frame_id == "r1/lidar"
    # Angles in the mount frame: ours minus the mount yaw; the beams spaced evenly between.
    first = scans[0][2]
    assert first.start_angle == pytest.approx(lidar.angles[0] - 0.5, abs=1e-12)
    assert first.end_angle == pytest.approx(lidar.angles[-1] - 0.5, abs=1e-12)
    assert len(first.ranges) == 90


def test_poses_and_transforms_equal_the_robots(recorded):
    sim, log = recorded.sim, recorded.log
    truth = [pose_xyt(m) for _, _, m in recorded.messages["/r1/ground_truth"]]
    assert np.allclose(truth, log.pose[:, 0], atol=1e-12)
    assert np.allclose(truth[-1], sim.robots["r1"].pose, atol=1e-12)
    odometry = [pose_xyt(m) for _, _, m in recorded.messages["/r1/odometry"]]
    assert np.allclose(odometry[-1], sim.robots["r1"].odometry.pose, atol=1e-12)
    last_time, _, tf = recorded.messages["/tf"][-1]
    assert last_time == 2 * 10**9
    frames = {(t.parent_frame_id, t.child_frame_id): t for t in tf.transforms}
    assert set(frames) == {("world", "r1/base_link"), ("r1/base_link", "r1/lidar"),
                           ("world", "r2/base_link")}
    base = frames[("world", "r1/base_link")]
    x, y, theta = sim.robots["r1"].pose
    assert (base.translation.x, base.translation.y) == pytest.approx((x, y), abs=1e-12)
    r = base.rotation
    assert quaternion_yaw(r.x, r.y, r.z, r.w) == pytest.approx(theta, abs=1e-12)
    mount = frames[("r1/base_link", "r1/lidar")]
    assert mount.translation.x == pytest.approx(0.1)
    assert quaternion_yaw(0, 0, mount.rotation.z, mount.rotation.w) == pytest.approx(0.5)


def test_scene_holds_arena_obstacles_robots(recorded):
    first = recorded.messages["/scene"][0][2]
    ids = {e.id for e in first.entities}
    assert ids == {"arena", "obstacle/0", "robot/r1", "robot/r2"}
    robot_entity = next(e for e in first.entities if e.id == "robot/r1")
    assert robot_entity.frame_id == "r1/base_link" and robot_entity.frame_locked
    arena = next(e for e in first.entities if e.id == "arena")
    assert len(arena.triangles) == 4 and len(arena.cylinders) == 1  # 4 walls, the fixed circle
    assert max(p.z for p in arena.triangles[0].points) == pytest.approx(0.4)  # wall height
    state = recorded.messages["/r1/state"][-1][2]
    assert state["v"] == pytest.approx(0.55, abs=0.01)  # mean of the wheel speeds
    assert state["command"] == pytest.approx([0.5, 0.6])


def test_events_goals_paths_grids_and_moving_obstacles(tmp_path):
    """A robot pushes a crate into a wall; its stand-in mapper and localizer get logged."""
    sim = Simulation.from_dict(scenario(
        [robot([0.5, 1.0, 0.0], name="r1", controller={"type": "waypoints",
                                                          "points": [[1.5, 1.0], [2.0, 1.0]]},
               goal={"position": [2.0, 1.0], "tolerance": 0.2})],
        [{"type": "box", "center": [1.2, 1.0], "size": [0.3, 0.3], "movable": True},
         {"type": "wall", "start": [3.0, 0.0], "end": [3.0, 2.0], "thickness": 0.1}],
        size=(4.0, 2.0)))
    r1 = sim.robots["r1"]
    grid = OccupancyGrid(np.full((4, 8), -1, dtype=np.int8), 0.5, (0.0, 0.0))
    r1.mapper = SimpleNamespace(grid=grid)

    class OffsetLocalizer:  # a stand-in estimate 5 cm beside the truth (the controller sees it)
        @property
        def pose(self):
            return r1.pose + [0.05, 0.0, 0.0]

    r1.localizer = OffsetLocalizer()
    logger = McapLogger(tmp_path / "run.mcap").attach(sim)
    sim.run(1.5)
    grid.data[0, 0] = 100  # the map learns something: it is sent again
    sim.run(1.5)
    logger.save()
    _, messages = read_mcap(tmp_path / "run.mcap")
    lines = [m.message for _, _, m in messages["/log"]]
    assert any("contact begins" in line for line in lines)  # the crate
    assert "r1: controller running -> arrived (reached the last waypoint)" in lines
    reached = [t for t, _, m in messages["/log"] if "goal reached" in m.message]
    assert reached == [round(r1.time_to_goal * 1e9)]
    # Moving obstacles are re-sent when they move (more often than the 1 s refresh).
    crate_updates = [t for t, _, u in messages["/scene"] if any(e.id == "obstacle/0"
                                                               for e in u.entities)]
    assert len(crate_updates) > 10
    goals = [e for _, _, u in messages["/scene"] for e in u.entities if e.id == "goal/r1"]
    assert goals[0].cylinders[0].size.x == pytest.approx(0.4)  # the tolerance disc
    grids = [m for _, _, m in messages["/r1/map"]]
    assert len(grids) == 2 and grids[0].column_count == 8 and grids[0].cell_size.x == 0.5
    assert grids[0].data[0] == 255 and grids[1].data[0] == 100  # int8 -1, then 100
    estimate = pose_xyt(messages["/r1/localization"][-1][2])
    assert np.allclose(estimate, r1.pose + [0.05, 0.0, 0.0], atol=1e-9)
    path = messages["/r1/path"][0][2]
    assert path.frame_id == "world"
    assert [(p.position.x, p.position.y) for p in path.poses] == [(1.5, 1.0), (2.0, 1.0)]


def test_an_aborted_log_leaves_nothing(tmp_path):
    sim = lidar_sim()
    logger = McapLogger(tmp_path / "run.mcap").attach(sim)
    sim.run(0.2)
    logger.abort()
    assert list(tmp_path.iterdir()) == []


def test_logging_a_minute_costs_less_than_the_run(tmp_path):
    import time

    sim = Simulation.from_file(None)
    logger = McapLogger(tmp_path / "run.mcap").attach(sim)
    started = time.process_time()  # CPU time: a loaded machine does not fail it
    sim.run(10.0)
    logger.save()
    elapsed = time.process_time() - started
    assert elapsed < 10.0 / 5  # well under the simulated time (measured: ~0.2 s)
    assert math.isclose(read_mcap(tmp_path / "run.mcap")[1]["/tf"][-1][0], 10e9)


def test_the_shipped_layout_shows_channels_the_default_scenario_has(tmp_path):
    import json
    import re
    from pathlib import Path

    layout = json.loads((Path(__file__).parents[2] / "docs" / "foxglove-layout.json").read_text())
    panels = {key.split("!")[0] for key in layout["configById"]}
    assert panels == {"3D", "Plot", "RosOut"}  # the 3D view, the speed plot, the log
    sim = Simulation.from_file(None)
    logger = McapLogger(tmp_path / "run.mcap").attach(sim)
    sim.run(0.5)
    logger.save()
    summary, messages = read_mcap(tmp_path / "run.mcap")
    topics = {c.topic for c in summary.channels.values()}
    three_d = layout["configById"]["3D!pymunkbot"]["topics"]
    optional = {"/r1/localization", "/r1/map"}  # only with a localizer or a mapper
    assert set(three_d) - optional <= topics
    for series in layout["configById"]["Plot!speeds"]["paths"]:
        topic, field, index = re.fullmatch(r"(/\w+/\w+)\.(\w+)(?:\[(\d)\])?",
                                           series["value"]).groups()
        value = messages[topic][-1][2][field]
        assert isinstance(value[int(index)] if index else value, float)
    assert layout["configById"]["RosOut!events"]["topicToRender"] == "/log"
