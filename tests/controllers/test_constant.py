"""Controllers that give one command for ever (``constant``: velocity, wheels) are asked once
while their robot keeps that command: a fleet of them costs no Python per robot and period.
A robot given back after a command by hand, or given another controller, is asked again."""
from __future__ import annotations

import math

import pytest

from pymunk_bot import Command, Simulation
from pymunk_bot.controllers.velocity import VelocityController


def one_robot() -> dict:
    return {"name": "constant", "world": {"size": [20.0, 20.0]},
            "robots": [{"name": "r", "pose": [5.0, 10.0, 0.0],
                        "controller": {"type": "velocity", "v": 0.5, "omega": 0.0}}]}


class Counting(VelocityController):
    """The velocity controller, counting how often it is asked."""

    asked = 0

    def compute(self, obs):
        Counting.asked += 1
        return super().compute(obs)


def test_a_constant_controller_is_asked_once_and_again_after_a_command_by_hand() -> None:
    sim = Simulation.from_dict(one_robot())
    robot = sim.robots["r"]
    robot.controller = Counting(robot.controller.config, robot.spec)
    Counting.asked = 0
    sim.run(2.0)  # 20 periods at 10 Hz
    assert Counting.asked == 1
    assert robot.pose[0] == pytest.approx(5.0 + 0.5 * 2.0, abs=0.05)  # it drove all along
    robot.command(Command(0.0, 0.0))  # stopped by hand: the controller waits
    sim.run(1.0)
    x = robot.pose[0]
    sim.run(1.0)
    assert robot.pose[0] == pytest.approx(x, abs=1e-3) and Counting.asked == 1
    robot.clear_command()  # given back: asked again, and the robot drives on
    sim.run(1.0)
    assert Counting.asked == 2
    assert robot.pose[0] > x + 0.3


def test_a_new_constant_controller_drives_the_robot_at_once() -> None:
    sim = Simulation.from_dict(one_robot())
    robot = sim.robots["r"]
    sim.run(1.0)
    config = robot.controller.config.model_copy(update={"v": 0.0, "omega": 1.0})
    robot.controller = VelocityController(config, robot.spec)
    heading = robot.pose[2]
    sim.run(1.0)
    assert math.remainder(robot.pose[2] - heading, math.tau) > 0.7  # turning (ramping up)


def test_a_velocity_controller_command_cannot_be_changed_in_place() -> None:
    sim = Simulation.from_dict(one_robot())
    with pytest.raises(AttributeError):
        sim.robots["r"].controller.command = Command(1.0, 0.0)
