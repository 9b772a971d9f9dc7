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
from pymunk_bot.planning.dwa import DwaParams, DynamicWindow, scan_points
from pymunk_bot.planning.tracking import MovingObstacleTracker, PassingSide
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec
from pymunk_bot.controllers.escape import Escape, to_robot_frame

PROGRESS_WINDOW = 10.0  # [s] without getting closer to the goal before the message says so


def dwa_params(config: DwaConfig, max_speed: float) -> DwaParams:
    """DWA tuning from a scenario's ``dwa`` section."""
    return DwaParams(horizon=config.horizon, time_samples=config.time_samples,
                     v_samples=config.v_samples, w_samples=config.w_samples,
                     safety=config.safety, heading_weight=config.heading_weight,
                     progress_weight=config.progress_weight,
                     clearance_weight=config.clearance_weight, speed_weight=config.speed_weight,
                     clearance_cap=config.clearance_cap, max_speed=max_speed,
                     allow_reverse=config.allow_reverse)


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
        self.escape = Escape()  # out of stalls where every arc toward the goal is blocked
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
        if self.gave_up(obs, -distance):  # a local minimum it cannot leave
            self.command = (0.0, 0.0)
            return STOP
        self.status = "running"
        self._report_progress(obs.time)
        # Approach the goal so as to stop on it: v <= sqrt(2 a d), gentler in the last metre.
        cap = min(math.sqrt(2.0 * 0.5 * obs.robot.max_accel * distance), 1.2 * distance)
        points = scan_points(obs.scan)
        velocities, oncoming = self.tracker.update(
            obs.scan.time, obs.pose, points, float(self.command[0]),
            obs.robot.radius + self.window.params.safety)
        target = self._passing_target(obs, oncoming, target)
        escape = self.escape.target(obs.pose, obs.time, points,
                                    obs.robot.radius + self.window.params.safety, target)
        v, omega = self.window.choose(*self.command, points,
                                      target if escape is None else escape, cap, velocities)
        self.escape.note(obs.time, v)
        self.command = (v, omega)
        return Command(v, omega)

    def _passing_target(self, obs: Observation, oncoming: tuple | None,
                        target: np.ndarray) -> np.ndarray:
        """DWA's target, swapped for a point beside something coming at us, on our right
        (see :class:`~pymunk_bot.planning.tracking.PassingSide`)."""
        return self.passing.target(obs.time, oncoming, target, obs.robot.radius)

    def _report_progress(self, now: float) -> None:
        """Say so while no progress is made (the watch fails the run after give_up_after)."""
        stalled = self.watch.stalled(now)
        if stalled > PROGRESS_WINDOW:
            # A reactive method can circle in a local minimum; say so while it keeps trying.
            self.message = f"no progress toward the goal for {stalled:.0f} s (stuck in a local minimum?)"
        elif self.message.startswith("no progress"):
            self.message = ""
