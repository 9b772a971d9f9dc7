"""A command set by hand holds the robot; given back, the controller's command holds again,
even one the controller returns unchanged (the drive is not told twice, but is told again)."""
from __future__ import annotations

from pymunk_bot import Simulation


def cruise() -> dict:
    return {"name": "cruise", "world": {"size": [20.0, 4.0], "duration": 10.0},
            "robots": [{"name": "r", "pose": [1.0, 2.0, 0.0],
                        "controller": {"type": "velocity", "v": 0.5, "omega": 0.0}}]}


def test_the_controller_drives_again_after_a_hand_command_is_cleared():
    sim = Simulation.from_dict(cruise())
    robot = sim.robots["r"]
    sim.run(1.0)
    assert robot.velocity[0] > 0.45  # cruising on the controller's command
    robot.set_velocity(0.0, 0.0)
    sim.run(1.0)
    stopped_at = float(robot.pose[0])
    assert abs(robot.velocity[0]) < 1e-6
    sim.run(0.5)
    assert abs(float(robot.pose[0]) - stopped_at) < 1e-6  # the hand command holds
    robot.clear_command()
    sim.run(1.0)
    assert robot.velocity[0] > 0.45  # the same command object, applied again
    assert float(robot.pose[0]) > stopped_at + 0.3
