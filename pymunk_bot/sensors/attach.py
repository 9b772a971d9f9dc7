"""Give a robot the sensors its config asks for (factories of the ``sensors`` registry)."""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import pymunk

from pymunk_bot.plugins import sensors as sensor_kinds
from pymunk_bot.sensors.bumper import Bumper
from pymunk_bot.sensors.crowd_state import CrowdStateSensor
from pymunk_bot.sensors.imu import Imu
from pymunk_bot.sensors.lidar import Lidar

if TYPE_CHECKING:
    from pymunk_bot.robots.robot import Robot


class World(Protocol):
    """What the sensors read of the world they are built in (physics/world.py's ``World``)."""

    obstacles: list[Any]
    time: float  # [s]

    def ray_caster(self) -> Any: ...
    def substep_for(self, body: pymunk.Body) -> float: ...


def make_lidar(config: Any, robot: "Robot", world: "World", rng: np.random.Generator) -> Lidar:
    """A LiDAR on the robot's body; it never sees the robot itself (the shape filter)."""
    lidar = Lidar(config, robot.body, robot.shape.filter, world.ray_caster(), rng)
    robot.fit("lidar", lidar)
    return lidar


def make_imu(config: Any, robot: "Robot", world: "World", rng: np.random.Generator) -> Imu:
    imu = Imu(config, robot.body, rng, substep=lambda: world.substep_for(robot.body))
    robot.fit("imu", imu)
    return imu


def make_crowd_state(config: Any, robot: "Robot", world: "World",
                     rng: np.random.Generator) -> CrowdStateSensor:
    """The pedestrians' true states (no noise: ``rng`` is unused)."""
    def walkers() -> list[Any]:
        return [o for o in world.obstacles if getattr(o.config, "type", "") == "pedestrian"]

    sensor = CrowdStateSensor(config, robot.body, walkers, clock=lambda: world.time)
    robot.fit("crowd_state", sensor)
    return sensor


def attach_sensors(robot: "Robot", world: "World", rng: np.random.Generator) -> None:
    """Create the robot's configured sensors with their own random streams, and its bumper.

    Each registered sensor kind draws from its own child of ``rng`` (always the same child,
    whether or not the others exist), and each takes its first reading now, at t = 0, so
    controllers have data from the first tick."""
    entries = sensor_kinds.entries()
    rngs = rng.spawn(len(entries))
    for entry, child in zip(entries, rngs):
        config = getattr(robot.config, entry.name, None)
        if config is not None:
            robot.sensors.append(sensor_kinds.get(entry.name)(config, robot, world, child))
    bumper = Bumper(robot.body, lambda: robot.collisions, clock=lambda: world.time)
    robot.fit("bumper", bumper)
    robot.sensors.append(bumper)
    for sensor in robot.sensors:
        sensor.update(0.0)
