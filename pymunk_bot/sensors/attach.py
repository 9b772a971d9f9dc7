"""Give a robot the sensors its config asks for."""
from __future__ import annotations

import numpy as np


def attach_sensors(robot, world, rng: np.random.Generator) -> None:
    """Create the robot's configured sensors (LiDAR, IMU, bumper) with their own RNG streams."""
    robot.sensors = []
