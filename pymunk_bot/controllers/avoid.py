"""Reactive obstacle avoidance toward a goal from the LiDAR: the Dynamic Window Approach.

See :mod:`pymunk_bot.planning.dwa` for the method and why we chose it. The controller knows only
its pose estimate (odometry unless the scenario grants ground truth), the goal and the latest
scan; it keeps the last command it gave as its velocity estimate, which the acceleration-limited
drive follows within a control period.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.config.controllers import AvoidControllerConfig, DwaConfig
from pymunk_bot.planning.dwa import DwaParams, DynamicWindow, free_runs, scan_points
from pymunk_bot.planning.tracking import MovingObstacleTracker, PassingSide
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec

PROGRESS_WINDOW = 10.0  # [s] without getting closer to the goal before the message says so
PROGRESS_STEP = 0.1  # [m] of progress that counts
STALL_SPEED = 0.02  # [m/s] DWA commands slower than this count as stalled
STALL_TIME = 1.0  # [s] stalled before an escape
ESCAPE_DISTANCE = 0.8  # [m] how far an escape aims along the free direction it picks
ESCAPE_TIME = 3.0  # [s] an escape gives up after this


def dwa_params(config: DwaConfig, max_speed: float) -> DwaParams:
    """DWA tuning from a scenario's ``dwa`` section."""
    return DwaParams(horizon=config.horizon, time_samples=config.time_samples,
                     v_samples=config.v_samples, w_samples=config.w_samples,
                     safety=config.safety, heading_weight=config.heading_weight,
                     progress_weight=config.progress_weight,
                     clearance_weight=config.clearance_weight, speed_weight=config.speed_weight,
                     clearance_cap=config.clearance_cap, max_speed=max_speed,
                     allow_reverse=config.allow_reverse)


def to_robot_frame(pose, point) -> np.ndarray:
    """A world point in the frame of a robot at ``pose`` (x forward, y left)."""
    x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
    dx, dy = float(point[0]) - x, float(point[1]) - y
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * dx + s * dy, -s * dx + c * dy])


class AvoidController(Controller):
    """Drives to the goal around whatever the LiDAR sees; needs a ``lidar`` on the robot."""

    def __init__(self, config: AvoidControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config, robot)
        if robot.drive != "diff":
            # The window searches the arcs of a robot that turns on its wheels' difference.
            raise ValueError(f"avoid drives diff robots only (this one is {robot.drive}); "
                             f"use navigate, go_to_goal or waypoints")
        self.window = DynamicWindow(robot, dwa_params(config.dwa, self.max_speed), 1.0 / config.rate)
        self.command = (0.0, 0.0)  # last (v, omega): our velocity estimate
        self._best_distance = math.inf
        self._best_time = 0.0
        self._stalled_since: float | None = None
        self._escape: tuple | None = None  # (world point [m], until [s])
        self.tracker = MovingObstacleTracker()
        self.passing = PassingSide()  # keeps right in head-on encounters

    def compute(self, obs: Observation) -> Command:
        goal = obs.goal  # the controller's own goal, or the robot's (see Observation)
        if goal is None:
            self.status, self.message = "failed", "no goal: set controller.goal or the robot's goal"
            return STOP
        if obs.scan is None:
            self.status, self.message = "failed", "avoid needs a lidar on the robot"
            return STOP
        target = to_robot_frame(obs.pose, goal)
        distance = float(np.hypot(*target))
        tolerance = self.config.tolerance if self.config.tolerance is not None else obs.goal_tolerance
        if distance <= 0.5 * tolerance:
            self.status, self.message = "arrived", ""
            self.command = (0.0, 0.0)
            return STOP
        self.status = "running"
        self._watch_progress(distance, obs.time)
        # Approach the goal so as to stop on it: v <= sqrt(2 a d), gentler in the last metre.
        cap = min(math.sqrt(2.0 * 0.5 * obs.robot.max_accel * distance), 1.2 * distance)
        points = scan_points(obs.scan)
        velocities, oncoming = self.tracker.update(
            obs.scan.time, obs.pose, points, float(self.command[0]),
            obs.robot.radius + self.window.params.safety)
        target = self._passing_target(obs, oncoming, target)
        target = self._escape_target(obs, points, target)
        v, omega = self.window.choose(*self.command, points, target, cap, velocities)
        self._stalled_since = None if v > STALL_SPEED else (
            obs.time if self._stalled_since is None else self._stalled_since)
        self.command = (v, omega)
        return Command(v, omega)

    def _passing_target(self, obs: Observation, oncoming: tuple | None,
                        target: np.ndarray) -> np.ndarray:
        """DWA's target, swapped for a point beside something coming at us, on our right
        (see :class:`~pymunk_bot.planning.tracking.PassingSide`)."""
        return self.passing.target(obs.time, oncoming, target, obs.robot.radius)

    def _escape_target(self, obs: Observation, points: np.ndarray, target: np.ndarray) -> np.ndarray:
        """DWA's target, swapped for a point along free space while escaping a stall.

        Beside an obstacle with the goal behind it, every arc toward the goal is blocked and
        turning away scores worse than standing still, so plain DWA freezes. After STALL_TIME
        we aim for a while at a point in the free direction nearest to the goal's bearing, then
        hand back to the goal.
        """
        if self._escape is not None:
            point, until = self._escape
            local = to_robot_frame(obs.pose, point)
            if obs.time < until and float(np.hypot(*local)) > 0.25:
                return local
            self._escape = None
        stalled = self._stalled_since is not None and obs.time - self._stalled_since >= STALL_TIME
        if not stalled:
            return target
        directions = np.linspace(-math.pi, math.pi, 72, endpoint=False)
        runs = free_runs(points, obs.robot.radius + self.window.params.safety, directions,
                         ESCAPE_DISTANCE)
        open_ = runs >= 0.75 * ESCAPE_DISTANCE
        if not open_.any():
            return target
        goal_bearing = math.atan2(target[1], target[0])
        off = np.abs((directions - goal_bearing + np.pi) % (2 * np.pi) - np.pi)
        off[~open_] = np.inf
        direction = float(directions[int(np.argmin(off))])
        local = ESCAPE_DISTANCE * np.array([math.cos(direction), math.sin(direction)])
        x, y, theta = (float(v) for v in obs.pose[:3])
        c, s_ = math.cos(theta), math.sin(theta)
        point = (x + c * local[0] - s_ * local[1], y + s_ * local[0] + c * local[1])
        self._escape = (point, obs.time + ESCAPE_TIME)  # fixed in the world while it lasts
        self._stalled_since = None
        return local

    def _watch_progress(self, distance: float, now: float) -> None:
        if distance < self._best_distance - PROGRESS_STEP:
            self._best_distance, self._best_time = distance, now
            self.message = ""
        elif now - self._best_time > PROGRESS_WINDOW:
            # A reactive method can circle in a local minimum for ever; say so (and keep trying).
            self.message = (f"no progress toward the goal for {now - self._best_time:.0f} s "
                            f"(stuck in a local minimum?)")
