"""Proportional go-to-goal: the seed's controller in SI units.

v = min(max_speed, k_rho * distance) * cos(bearing)+, omega = k_alpha * bearing, where bearing is
the goal's angle relative to the heading. Forward speed fades out while the robot faces away, so
it turns toward the goal before it drives.
"""
from __future__ import annotations

import math

from ..config.controllers import GoToGoalControllerConfig
from ..geometry import wrap_angle
from .base import STOP, Command, Controller, Observation, RobotSpec


class GoToGoalController(Controller):
    """Steers straight at one goal point and stops inside the tolerance."""

    def __init__(self, config: GoToGoalControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config, robot)

    def compute(self, obs: Observation) -> Command:
        goal = obs.goal  # the controller's own goal, or the robot's (see Observation)
        if goal is None:
            self.status, self.message = "failed", "no goal: set controller.goal or the robot's goal"
            return STOP
        x, y, theta = obs.pose
        dx, dy = goal[0] - x, goal[1] - y
        distance = math.hypot(dx, dy)
        tolerance = self.config.tolerance if self.config.tolerance is not None else obs.goal_tolerance
        # Stop a little inside the tolerance so a slightly noisy estimate still lands inside it.
        if distance <= 0.5 * tolerance:
            self.status = "arrived"
            return STOP
        self.status = "running"
        bearing = wrap_angle(math.atan2(dy, dx) - theta)
        v = min(self.max_speed, self.config.k_rho * distance) * max(0.0, math.cos(bearing))
        omega = self.config.k_alpha * bearing
        return Command(v, omega)
