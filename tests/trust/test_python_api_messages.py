"""The Python API says what is wrong as the YAML does: text is not a number, a goal must lie in
the arena, a missing robot names the robots, and `dir(pymunk_bot)` shows only the API."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import pymunk_bot as pb
from pymunk_bot.robots.robot import RobotsByName


@pytest.fixture(scope="module")
def robot():
    sim = pb.Simulation.from_dict({"name": "api", "world": {"size": [6.0, 4.0]},
                                   "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0]}]})
    return sim.robots["r1"]


@pytest.mark.parametrize("call, error, fragment", [
    (lambda r: r.set_velocity("0.5", 0), TypeError, "v must be a number (got str '0.5')"),
    (lambda r: r.set_velocity(0.5, None), TypeError, "omega must be a number"),
    (lambda r: r.set_velocity(True, 0), TypeError, "v must be a number"),
    (lambda r: r.set_velocity(float("nan"), 0), ValueError, "v must be finite"),
    (lambda r: r.set_wheel_speeds("1", 1), TypeError, "left must be a number"),
    (lambda r: r.set_goal((100, 100)), ValueError, "outside the arena [0, 6] x [0, 4]"),
    (lambda r: r.set_goal("ab"), TypeError, "goal must be (x, y)"),
    (lambda r: r.set_goal(("1", 2)), TypeError, "goal[0] must be a number"),
    (lambda r: r.set_goal((1, 1), tolerance=0), ValueError, "tolerance must be > 0"),
    (lambda r: r.set_nav_goal((-1, 2)), ValueError, "outside the arena"),
])
def test_bad_values_from_code_are_refused_with_their_name(robot, call, error, fragment):
    with pytest.raises(error) as caught:
        call(robot)
    assert fragment in str(caught.value)


def test_good_values_from_code_are_taken(robot):
    robot.set_velocity(np.float32(0.2), np.int64(0))
    robot.set_goal((5.0, 3.0), tolerance=0.3)
    assert robot.goal == (5.0, 3.0) and robot.goal_tolerance == 0.3
    robot.clear_command()


def test_a_missing_robot_names_the_robots():
    robots = RobotsByName(r1=1, r2=2)
    with pytest.raises(KeyError) as caught:
        robots["r3x"]
    assert "no robot named 'r3x'" in str(caught.value) and "'r1', 'r2'" in str(caught.value)
    assert robots.get("nope") is None and "r1" in robots


def test_dir_of_the_package_is_its_api():
    out = subprocess.run([sys.executable, "-c", "import pymunk_bot; print(dir(pymunk_bot))"],
                         capture_output=True, text=True, check=True).stdout
    for helper in ("Any", "TYPE_CHECKING", "importlib", "annotations"):
        assert f"'{helper}'" not in out
    for name in pb.__all__:
        assert f"'{name}'" in out


def test_a_simulation_names_its_robots_when_asked_for_a_missing_one_and_in_its_repr():
    sim = pb.Simulation.from_dict({"name": "api", "world": {"size": [6.0, 4.0]},
                                   "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0]},
                                              {"name": "r2", "pose": [3.0, 1.0, 0.0]}]})
    with pytest.raises(KeyError, match="no robot named 'r3'; the robots are: 'r1', 'r2'"):
        sim.robots["r3"]
    sim.step()
    assert repr(sim) == ("Simulation('api', seed=0, t=0.017 s of 30 s, dt=0.01667 s x "
                         f"{sim.substeps} substeps, robots: r1, r2)")


def test_a_sensor_the_robot_was_not_given_names_the_key_to_add(robot):
    # The default robot has no LiDAR and no IMU: reading one says which key to add, not
    # "'NoneType' object has no attribute 'scan'".
    with pytest.raises(AttributeError) as caught:
        robot.lidar.scan()
    message = str(caught.value)
    assert "robot 'r1' has no lidar: add `lidar:` to its entry under `robots:`" in message
    assert "(its sensors: bumper)" in message
    assert not hasattr(robot, "imu") and robot.sensor("imu") is None
    assert robot.bumper is robot.sensor("bumper")


def test_a_fitted_lidar_is_there_by_either_name():
    sim = pb.Simulation.from_dict({"name": "api", "world": {"size": [6.0, 4.0]},
                                   "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0],
                                               "lidar": {"beams": 8}}]})
    r = sim.robots["r1"]
    assert r.lidar is r.sensor("lidar") and len(r.lidar.scan()) == 8
