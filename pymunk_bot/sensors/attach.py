"""Give a robot the sensors its config asks for."""
from __future__ import annotations

import weakref
from typing import TYPE_CHECKING

import numpy as np
import pymunk

from .bumper import Bumper
from .imu import Imu
from .lidar import Lidar

if TYPE_CHECKING:
    from ..robot import Robot
    from ..world import World

# One caster per Space, so robots in one world share its cached geometry. The LiDARs keep their
# caster alive; this map only finds it (weak values: a dropped world frees its caster). A caster
# refers to its Space, and the Space to the World, so a map keyed by either would never let go.
_casters: weakref.WeakValueDictionary = weakref.WeakValueDictionary()


def ray_caster(space: pymunk.Space):
    """The shared :class:`~pymunk_bot.sensors.raycast.RayCaster` of a Space."""
    caster = _casters.get(id(space))
    if caster is None or caster.space is not space:  # an id can be reused by a later Space
        # Imported here: only worlds with a LiDAR pay for the caster's geometry tables.
        from .raycast import RayCaster
        caster = RayCaster(space)
        _casters[id(space)] = caster
    return caster


def attach_sensors(robot: "Robot", world: "World", rng: np.random.Generator) -> None:
    """Create the robot's configured sensors (LiDAR, IMU, bumper) with their own RNG streams.

    Every robot has a bumper; LiDAR and IMU only when configured. Each sensor draws from its own
    child of ``rng`` (always the same child, whether or not the others exist), and each takes
    its first reading now, at t = 0, so controllers have data from the first tick.
    """
    lidar_rng, imu_rng = rng.spawn(2)
    config = robot.config
    robot.sensors = []
    robot.lidar = robot.imu = None
    if config.lidar is not None:
        robot.lidar = Lidar(config.lidar, robot.body, robot.shape.filter, ray_caster(world.space),
                            lidar_rng)
        robot.sensors.append(robot.lidar)
    if config.imu is not None:
        substep = world.config.world.dt / world.substeps
        robot.imu = Imu(config.imu, robot.body, imu_rng, substep=substep)
        robot.sensors.append(robot.imu)
    robot.bumper = Bumper(robot.body, lambda: robot.collisions)
    robot.sensors.append(robot.bumper)
    for sensor in robot.sensors:
        sensor.update(0.0)
