"""A robot: its pymunk body, drive, sensors, controller and bookkeeping."""
from __future__ import annotations

import math

import numpy as np
import pymunk

from . import physics
from .config.schema import RobotConfig
from .drive import DiffDrive
from .readings import RobotSpec
from .controllers.base import wheel_speeds
from .sensors.odometry import Odometry


class Robot:
    """A differential-drive disc robot. ``pose`` is ground truth; sensors give what it knows."""

    def __init__(self, config: RobotConfig, space: pymunk.Space, group: int,
                 rng: np.random.Generator) -> None:
        self.config = config
        self.name = config.name
        self.radius = config.radius
        self.spec = RobotSpec(config.name, config.radius, config.track_width,
                              config.max_wheel_speed, config.max_accel)
        x, y, theta = config.pose
        self.body = pymunk.Body(config.mass, pymunk.moment_for_circle(config.mass, 0, config.radius))
        self.body.position = (x, y)
        self.body.angle = theta
        self.shape = pymunk.Circle(self.body, config.radius)
        self.shape.friction = config.friction
        self.shape.collision_type = physics.ROBOT
        # The group keeps the robot's own LiDAR from seeing its own body.
        self.shape.filter = pymunk.ShapeFilter(group=group)
        space.add(self.body, self.shape)
        self.drive = DiffDrive(space, self.body, config.track_width, config.max_wheel_speed,
                               config.max_accel)
        self.odometry = Odometry(config.odometry, config.pose, config.track_width, rng)
        self.sensors: list = []  # everything with update(time), in the order they read
        self.lidar = None  # set by sensors.attach when configured
        self.imu = None
        self.bumper = None
        self.controller = None
        self.metrics = None
        self.goal: tuple[float, float] | None = (
            tuple(config.goal.position) if config.goal is not None else None)
        self.goal_tolerance = config.goal.tolerance if config.goal is not None else 0.2
        self.nav_goal = self.goal  # where the controller drives: its own goal, else the task's
        self.collisions = 0  # contact episodes so far
        self.distance = 0.0  # true path length [m]
        self.time_to_goal: float | None = None
        self.distance_to_goal: float | None = None  # path length when the goal was reached [m]
        self._override: tuple[float, float] | None = None
        self._travel = [0.0, 0.0]  # wheel travel in the current tick [m]
        self._last_position = (x, y)

    # ------------------------------------------------------------------ state
    @property
    def pose(self) -> np.ndarray:
        """Ground-truth pose [x, y, theta] (theta unwrapped: it counts whole turns)."""
        p = self.body.position
        return np.array([p.x, p.y, self.body.angle])

    @property
    def velocity(self) -> np.ndarray:
        """Ground-truth (v forward [m/s], omega [rad/s])."""
        vx, vy = self.body.velocity
        theta = self.body.angle
        return np.array([vx * math.cos(theta) + vy * math.sin(theta), self.body.angular_velocity])

    @property
    def goal_reached(self) -> bool:
        return self.time_to_goal is not None

    def set_goal(self, position: tuple[float, float], tolerance: float | None = None) -> None:
        """A new task goal (e.g. a click in the viewer); the controller drives there too."""
        self.goal = self.nav_goal = (float(position[0]), float(position[1]))
        if tolerance is not None:
            self.goal_tolerance = tolerance
        self.time_to_goal = self.distance_to_goal = None

    def readings(self) -> dict:
        """Latest readings of the sensors beyond LiDAR and odometry, by name (e.g. "imu")."""
        return {s.name: s.reading for s in self.sensors if s is not self.lidar}

    # ------------------------------------------------------------------ commands
    def set_wheel_speeds(self, left: float, right: float) -> None:
        """Drive with these wheel speeds [m/s] until ``clear_wheel_speeds``; the controller waits."""
        self._override = (float(left), float(right))
        self.drive.set_wheel_speeds(*self._override)

    def set_velocity(self, v: float, omega: float, vy: float = 0.0) -> None:
        """Drive at body-frame forward speed v [m/s] and yaw rate omega [rad/s] until
        :meth:`clear_command`; the controller waits. ``vy`` (lateral) is for omni drives only."""
        if vy != 0.0:
            raise ValueError(f"a {self.config.drive} drive cannot move sideways (vy = {vy})")
        left, right = wheel_speeds(float(v), float(omega), self.config.track_width)
        self.set_wheel_speeds(left, right)

    def clear_command(self) -> None:
        """Give the robot back to its controller."""
        self._override = None

    clear_wheel_speeds = clear_command

    @property
    def overridden(self) -> bool:
        return self._override is not None

    # ------------------------------------------------------------------ tick parts
    def before_substep(self, h: float) -> None:
        self.drive.before_substep(h)
        left, right = self.drive.wheel_speeds
        self._travel[0] += left * h
        self._travel[1] += right * h

    def after_step(self, time: float) -> None:
        """Bookkeeping once all substeps of a tick are done."""
        self.odometry.update(*self._travel)
        self._travel = [0.0, 0.0]
        p = self.body.position
        self.distance += math.hypot(p.x - self._last_position[0], p.y - self._last_position[1])
        self._last_position = (p.x, p.y)
        if self.goal is not None and self.time_to_goal is None:
            if math.hypot(p.x - self.goal[0], p.y - self.goal[1]) <= self.goal_tolerance:
                self.time_to_goal = time
                self.distance_to_goal = self.distance
