"""``navigate`` for every drive: cars plan drivable paths (Hybrid A*), the others grid A*."""
from __future__ import annotations

from typing import Any

from pymunk_bot.config.controllers import NavigateControllerConfig
from pymunk_bot.robots.readings import RobotSpec


def make_navigate(config: NavigateControllerConfig, robot: RobotSpec) -> Any:
    """The navigation controller that suits the robot's drive."""
    if robot.min_turn_radius > 0:
        from pymunk_bot.controllers.car_navigate import CarNavigateController
        return CarNavigateController(config, robot)
    from pymunk_bot.controllers.navigate import NavigateController
    return NavigateController(config, robot)
