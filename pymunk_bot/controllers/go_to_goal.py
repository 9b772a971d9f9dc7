"""Proportional go-to-goal: the seed's controller in SI units.

v = min(max_speed, k_rho * distance) * cos(bearing)+, omega = k_alpha * bearing, where bearing is
the goal's angle relative to the heading. Forward speed fades out while the robot faces away, so
it turns toward the goal before it drives.
"""
from __future__ import annotations

import math

from pymunk_bot.config.controllers import GoToGoalControllerConfig
from pymunk_bot.geometry.plane import wrap_angle
from pymunk_bot.planning.steering import car_pursue, holonomic_toward
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec


REVERSE_CLEARANCE = 1.15  # a car backs up until the goal is this many turning radii from the
# centre of the circle it would turn on toward it


class GoToGoalController(Controller):
    """Steers straight at one goal point and stops inside the tolerance.

    An omni robot slides straight at the goal while it turns to face it; a car pursues the
    goal along arcs no tighter than its turning circle, and backs up (steering the other way)
    when the goal lies inside a turning circle it cannot reach forward."""

    def __init__(self, config: GoToGoalControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config, robot)
        self.robot = robot
        self._reversing = False

    def compute(self, obs: Observation) -> Command:
        goal = obs.goal  # the controller's own goal, or the robot's (see Observation)
        if goal is None:
            self.status, self.message = "failed", "no goal: set controller.goal or the robot's goal"
            return STOP
        hold = self.hold_until_localized(obs)  # localize before driving (Controller)
        if hold is not None:
            return hold
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
        speed = min(self.max_speed, self.config.k_rho * distance)
        if self.robot.holonomic:
            return holonomic_toward(obs.pose, goal, speed, math.atan2(dy, dx),
                                    self.robot.max_omega, 1.0 / self.rate)
        if self.robot.min_turn_radius > 0:
            return self._car(obs.pose, goal, speed, bearing)
        v = min(self.max_speed, self.config.k_rho * distance) * max(0.0, math.cos(bearing))
        omega = self.config.k_alpha * bearing
        return Command(v, omega)

    def _car(self, pose, goal, speed: float, bearing: float) -> Command:
        """Forward pursuit; while the goal lies inside the turning circle on its side (it cannot
        be reached forward), back up with the wheels turned the other way, which swings the
        nose toward the goal (the middle leg of a three-point turn)."""
        r = self.robot.min_turn_radius
        x, y, theta = (float(v) for v in pose[:3])
        side = math.copysign(1.0, bearing)
        centre = (x - side * r * math.sin(theta), y + side * r * math.cos(theta))
        gap = math.dist(centre, goal)
        if gap < r:
            self._reversing = True
        elif gap > REVERSE_CLEARANCE * r:
            self._reversing = False
        if self._reversing:
            return Command(-speed, side * speed / r)
        return car_pursue(pose, goal, speed, r)
