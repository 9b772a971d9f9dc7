"""Run logs hold what happened, step by step, and read back exactly; bad files give one line."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.runlog import RunLogger, load_log
from viewer_helpers import build, wheels


def lidar_run(duration=2.0):
    sim = build([{"name": "r", "pose": [1.0, 1.5, 0.0], "controller": wheels(0.5, 0.6),
                  "lidar": {"beams": 40, "max_range": 3.0, "rate": 10.0},
                  "odometry": {"right_scale_error": 0.05}},
                 {"name": "s", "pose": [3.2, 0.5, 1.0]}],
                obstacles=[{"type": "box", "center": [2.5, 2.5], "size": [0.4, 0.4],
                            "movable": True}])
    logger = RunLogger().attach(sim)
    sim.run(duration)
    return sim, logger


def test_the_log_holds_every_step_of_every_robot(tmp_path):
    sim, logger = lidar_run()
    path = tmp_path / "run.npz"
    logger.save(path)
    log = load_log(path)
    assert log.robot_names == ["r", "s"]
    assert log.time.shape == (121,)
    assert log.time[0] == 0.0 and log.time[-1] == pytest.approx(2.0)
    assert log.pose.shape == (121, 2, 3)
    assert np.array_equal(log.pose[-1, 0], sim.robots["r"].pose)
    assert np.array_equal(log.odometry[-1, 0], sim.robots["r"].odometry.pose)
    assert np.array_equal(log.pose[0, 1], [3.2, 0.5, 1.0])
    # The scale error makes odometry drift from the truth; both are in the log.
    assert np.hypot(*(log.odometry[-1, 0, :2] - log.pose[-1, 0, :2])) > 0.01
    # Commands: the wheels controller's speeds; the idle robot's are zero.
    assert log.command[-1, 0] == pytest.approx((0.5, 0.6))
    assert np.all(log.command[:, 1] == 0.0)
    assert log.velocity[-1, 0, 0] == pytest.approx(0.55, abs=1e-4)
    assert log.obstacle_pose.shape == (121, 1, 3)


def test_scans_are_logged_at_the_sensor_rate_with_their_pose(tmp_path):
    sim, logger = lidar_run()
    logger.save(tmp_path / "run.npz")
    log = load_log(tmp_path / "run.npz")
    assert set(log.scans) == {"r"}  # "s" has no LiDAR
    scans = log.scans["r"]
    assert scans.time == pytest.approx(np.arange(21) * 0.1)
    assert scans.ranges.shape == (21, 40)
    assert np.allclose(scans.ranges[-1], sim.robots["r"].lidar.ranges, atol=1e-6)
    # Each scan's pose is the robot's true pose at the step it was taken.
    for k, t in enumerate(scans.time):
        row = int(np.argmin(np.abs(log.time - t)))
        assert np.array_equal(scans.pose[k], log.pose[row, 0])
    assert scans.angles == pytest.approx(sim.robots["r"].lidar.angles)


def test_pushed_obstacles_are_logged_as_they_move(tmp_path):
    sim = build([{"name": "r", "pose": [0.5, 1.5, 0.0], "controller": wheels(0.8, 0.8)}],
                obstacles=[{"type": "box", "center": [1.5, 1.5], "size": [0.3, 0.3],
                            "movable": True, "mass": 0.5}])
    logger = RunLogger().attach(sim)
    sim.run(2.5)
    log = logger.log()
    start, end = log.obstacle_pose[0, 0], log.obstacle_pose[-1, 0]
    assert end[0] - start[0] > 0.5
    assert log.collisions[-1, 0] >= 1


def test_the_log_names_the_goal_and_teleop_over_time():
    sim = build([{"name": "r", "pose": [1.0, 1.5, 0.0], "controller": {"type": "go_to_goal"},
                  "goal": {"position": [3.0, 1.5]}}])
    logger = RunLogger().attach(sim)
    sim.run(0.5)
    sim.robots["r"].set_goal((2.0, 2.5))
    sim.robots["r"].set_wheel_speeds(0.1, 0.1)
    sim.run(0.5)
    log = logger.log()
    assert log.goal[0, 0] == pytest.approx((3.0, 1.5))
    assert log.goal[-1, 0] == pytest.approx((2.0, 2.5))
    assert not log.teleop[0, 0] and log.teleop[-1, 0]


@pytest.mark.parametrize("content, problem", [
    (None, "file not found"),
    (b"not a zip at all", "not a run log"),
])
def test_bad_files_give_one_line(tmp_path, content, problem):
    path = tmp_path / "bad.npz"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(ScenarioError) as info:
        load_log(path)
    assert problem in str(info.value)
    assert "\n" not in str(info.value)


def test_an_npz_that_is_not_a_run_log(tmp_path):
    path = tmp_path / "other.npz"
    np.savez(path, x=np.arange(3))
    with pytest.raises(ScenarioError, match="not a run log"):
        load_log(path)
    np.savez(path, meta=np.array('{"format": "pymunk-bot run log", "version": 99}'))
    with pytest.raises(ScenarioError, match="version 99"):
        load_log(path)


def test_a_damaged_log_is_reported_not_crashed_on(tmp_path):
    _, logger = lidar_run(0.2)
    good = tmp_path / "good.npz"
    logger.save(good)
    with np.load(good) as data:
        arrays = dict(data.items())
    arrays["meta"] = np.array(str(arrays["meta"]).replace('"name"', '"nome"'))
    np.savez(tmp_path / "bad_meta.npz", **arrays)
    with pytest.raises(ScenarioError, match="damaged"):
        load_log(tmp_path / "bad_meta.npz")
    with np.load(good) as data:
        arrays = dict(data.items())
    arrays["pose"] = arrays["pose"][:-3]
    np.savez(tmp_path / "short.npz", **arrays)
    with pytest.raises(ScenarioError, match="damaged"):
        load_log(tmp_path / "short.npz")
