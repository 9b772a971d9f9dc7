"""What a fleet's controllers see, when many are due in one tick: each observation is a
snapshot of its period (its pose and odometry are its own arrays, later ticks never change
them), and a localizer swapped in while running is the one observed."""
from __future__ import annotations

import numpy as np

from pymunk_bot import Command, Simulation


def fleet(n: int = 6) -> dict:
    return {"name": "fleet", "world": {"size": [20.0, 20.0], "duration": 10.0},
            "robots": [{"name": f"r{k}", "pose": [2.0, 2.0 + 3.0 * k, 0.0],
                        "controller": {"type": "velocity", "v": 0.4, "omega": 0.2}}
                       for k in range(n)]}


class Recorder:
    """Drives like the velocity controller and keeps every observation with what the robot's
    odometry and localizer said when it was made."""

    rate = 10.0

    def __init__(self, robot) -> None:
        self.robot = robot
        self.seen: list[tuple] = []

    def compute(self, obs):
        self.seen.append((obs, self.robot.odometry.pose, self.robot.localizer.pose))
        return Command(0.4, 0.2)


class FixedLocalizer:
    """A localizer that always reports one pose."""

    pose = np.array([7.0, 8.0, 0.5])


def test_each_observation_is_a_snapshot_of_its_period():
    sim = Simulation.from_dict(fleet())
    recorders = {name: Recorder(robot) for name, robot in sim.robots.items()}
    for name, recorder in recorders.items():
        sim.robots[name].controller = recorder
    sim.run(2.0)
    for recorder in recorders.values():
        assert len(recorder.seen) == 20  # 10 Hz for 2 s, every robot due in the same ticks
        for obs, odometry, estimate in recorder.seen:
            assert np.array_equal(obs.odometry, odometry)  # as it was then, not as it is now
            assert np.array_equal(obs.pose, estimate)
            assert obs.pose is not obs.odometry
        first = recorder.seen[0][0]
        assert not np.array_equal(first.odometry, recorder.seen[-1][0].odometry)  # it moved
    obs = recorders["r0"].seen[-1][0]
    before = obs.odometry.copy()
    obs.pose[0] += 100.0  # a controller that edits its observation's pose in place
    assert np.array_equal(obs.odometry, before)
    assert np.array_equal(recorders["r1"].seen[-1][0].pose, recorders["r1"].seen[-1][2])


def test_a_localizer_swapped_in_while_running_is_what_the_controller_sees():
    sim = Simulation.from_dict(fleet())
    recorder = Recorder(sim.robots["r3"])
    sim.robots["r3"].controller = recorder
    sim.run(0.5)
    sim.robots["r3"].localizer = FixedLocalizer()
    sim.run(0.5)
    assert np.array_equal(recorder.seen[-1][0].pose, FixedLocalizer.pose)
    assert not np.array_equal(recorder.seen[0][0].pose, FixedLocalizer.pose)
