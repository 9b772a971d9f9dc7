"""Checks a file's keys allow but its meaning does not: things outside the arena, controllers
that cannot work with what the robot carries, grids too big for memory, angles in degrees.

``check(scenario)`` raises :class:`~pymunk_bot.config.errors.SemanticError` (exit 2); ``angle_warnings``
returns the doubtful angles (a warning, the run goes on). ``check_seed`` guards the Python API.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

from pymunk_bot.config.errors import SemanticError
from pymunk_bot.config.controllers import (
    CrowdNavOrcaControllerConfig,
    AvoidControllerConfig, GoToGoalControllerConfig, NavigateControllerConfig,
    PolicyControllerConfig, WaypointsControllerConfig,
)
from pymunk_bot.config.schema import RobotConfig, ScenarioConfig
from pymunk_bot.config.outlines import distance_to_obstacle, is_round, obstacle_outline

MAX_GRID_CELLS = 4_000_000  # planning grid cells (a 200 m x 200 m arena at 0.1 m): ~100 MB
MAX_SEED = 2**63 - 1


def check_seed(seed: object) -> int | None:
    """A seed for the Python API: None, or an integer in [0, 2**63 - 1].

    Raises TypeError for a non-integer (1.7 is not silently 1) and ValueError when out of range.
    """
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise TypeError(f"seed must be an integer (got {seed!r})")
    if not 0 <= int(seed) <= MAX_SEED:
        raise ValueError(f"seed must be in [0, 2**63 - 1] (got {seed})")
    return int(seed)


def check(scenario: ScenarioConfig) -> None:
    """Raise SemanticError for the first problem found."""
    extent = _arena_extent(scenario)
    for i, obstacle in enumerate(scenario.obstacles):
        _check_obstacle_in_arena(i, obstacle, extent)
    for i, robot in enumerate(scenario.robots):
        _check_controller(i, robot, scenario)
    _check_events(scenario, extent)


def _check_events(scenario: ScenarioConfig, extent: tuple[float, float, float, float]) -> None:
    """Every event names a robot of the scenario and teleports it inside the arena."""
    names = [r.name for r in scenario.robots]
    for k, event in enumerate(scenario.events):
        if event.robot not in names:
            from pymunk_bot.config.messages import did_you_mean
            raise SemanticError(("events", k, "robot"), f"no robot '{event.robot}' in the "
                                f"scenario{did_you_mean(event.robot, names)}")
        if _outside(event.teleport[:2], extent):
            x, y = event.teleport[:2]
            raise SemanticError(("events", k, "teleport"), f"({x:g}, {y:g}) is outside the "
                                f"arena {_span(extent)}")


def _arena_size(scenario: ScenarioConfig) -> tuple[float, float]:
    """The arena's (width, height) [m]; parse_scenario fills it in from a map before the checks."""
    if scenario.world.size is None:
        raise SemanticError(("world",), "the world needs a 'size' or a 'map'")
    width, height = scenario.world.size
    return width, height


def _arena_extent(scenario: ScenarioConfig) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) [m] of the arena: [0, w] x [0, h], or a map's extent (its ``origin``)."""
    _arena_size(scenario)  # the clear error when neither size nor map is given
    return scenario.world.extent


def _span(extent: tuple[float, float, float, float]) -> str:
    x0, y0, x1, y1 = extent
    return f"[{x0:g}, {x1:g}] x [{y0:g}, {y1:g}]"


def _check_obstacle_in_arena(index: int, obstacle, extent: tuple[float, float, float, float]) -> None:
    if is_round(obstacle):
        (cx, cy), r = obstacle.center, obstacle.radius
        low, high = np.array([cx - r, cy - r]), np.array([cx + r, cy + r])
    else:
        outline = obstacle_outline(obstacle)
        if outline is None:  # every obstacle but a circle has an outline
            raise SemanticError(("obstacles", index), f"unknown obstacle type {obstacle.type!r}")
        low, high = outline.min(axis=0), outline.max(axis=0)
    x0, y0, x1, y1 = extent
    if high[0] <= x0 or high[1] <= y0 or low[0] >= x1 or low[1] >= y1:
        raise SemanticError(
            ("obstacles", index),
            f"{obstacle.type} lies outside the arena {_span(extent)} "
            f"(it spans [{low[0]:g}, {high[0]:g}] x [{low[1]:g}, {high[1]:g}])")


def _outside(point, extent: tuple[float, float, float, float]) -> bool:
    x0, y0, x1, y1 = extent
    return not (x0 <= point[0] <= x1 and y0 <= point[1] <= y1)


def _check_controller(index: int, robot: RobotConfig, scenario: ScenarioConfig) -> None:
    controller = robot.controller
    loc = ("robots", index, "controller")
    extent = _arena_extent(scenario)
    if isinstance(controller, WaypointsControllerConfig):
        for k, point in enumerate(controller.points):
            if _outside(point, extent):
                raise SemanticError(loc + ("points", k),
                                    f"({point[0]:g}, {point[1]:g}) is outside the arena "
                                    f"{_span(extent)}")
    needs_goal = (GoToGoalControllerConfig, AvoidControllerConfig, NavigateControllerConfig,
                  CrowdNavOrcaControllerConfig)
    if isinstance(controller, needs_goal) and controller.goal is None and robot.goal is None:
        raise SemanticError(loc, f"{controller.type} needs a goal: set controller.goal or the "
                                 "robot's goal")
    if isinstance(controller, CrowdNavOrcaControllerConfig) \
            and getattr(robot, "crowd_state", None) is None:
        raise SemanticError(loc, "crowdnav_orca reads the pedestrians' true states: add "
                                 "'crowd_state: {}' to the robot")
    if isinstance(controller, AvoidControllerConfig) and robot.lidar is None:
        raise SemanticError(loc, "avoid steers by the LiDAR: add a 'lidar' to the robot")
    if isinstance(controller, NavigateControllerConfig):
        _check_navigate(index, robot, controller, scenario)
    if isinstance(controller, PolicyControllerConfig):
        if problem := controller.misfit(robot):
            raise SemanticError(loc, problem)
        _check_plan_guidance(index, robot, controller, scenario)


def too_many_cells(width: float, height: float, resolution: float) -> str | None:
    """What is wrong with planning a ``width`` x ``height`` m arena on a grid of ``resolution``
    [m], or None: more cells than MAX_GRID_CELLS (every planner's bound)."""
    cells = math.ceil(width / resolution) * math.ceil(height / resolution)
    if cells <= MAX_GRID_CELLS:
        return None
    return (f"a {width:g} m x {height:g} m arena at {resolution:g} m is {cells} planning cells "
            f"(at most {MAX_GRID_CELLS}); use a coarser resolution")


def _check_plan_guidance(index: int, robot: RobotConfig, controller: PolicyControllerConfig,
                         scenario: ScenarioConfig) -> None:
    """A plan-guided policy needs a map given in advance, and a planning grid of bounded size."""
    guidance = controller.guidance()
    if guidance is None:
        return
    loc = ("robots", index, "controller", "plan_guidance")
    if getattr(robot.localization, "type", robot.localization) == "slam":
        raise SemanticError(loc, f"plan guidance plans on the map the robot is given, and "
                                 f"localization 'slam' starts with none: set robots[{index}]."
                                 "localization to ground_truth, odometry, mcl or ekf (or turn "
                                 "plan_guidance off)")
    problem = too_many_cells(*_arena_size(scenario), guidance.resolution)
    if problem is not None:
        raise SemanticError(loc + ("resolution",), problem)


def _check_navigate(index: int, robot: RobotConfig, controller: NavigateControllerConfig,
                    scenario: ScenarioConfig) -> None:
    loc = ("robots", index, "controller")
    problem = too_many_cells(*_arena_size(scenario), controller.resolution)
    if problem is not None:
        raise SemanticError(loc + ("resolution",), problem)
    unmapped = [o.type for o in scenario.obstacles
                if getattr(o, "movable", False) and not controller.map_movable]
    if robot.lidar is None and (unmapped or len(scenario.robots) > 1):
        what = "movable obstacles" if unmapped else "the other robots"
        raise SemanticError(loc, f"navigate needs a 'lidar' on the robot to avoid {what}, "
                                 "which are not on its map")
    if controller.goal is not None:
        goal, goal_loc = controller.goal, loc + ("goal",)
    elif robot.goal is not None:
        goal, goal_loc = robot.goal.position, ("robots", index, "goal", "position")
    else:  # _check_controller refused this already
        raise SemanticError(loc, "navigate needs a goal: set controller.goal or the robot's goal")
    for k, obstacle in enumerate(scenario.obstacles):
        if getattr(obstacle, "movable", False):
            continue
        if distance_to_obstacle(goal, obstacle) < robot.radius:
            raise SemanticError(goal_loc, f"({goal[0]:g}, {goal[1]:g}) is inside or within the "
                                          f"robot's radius of obstacles[{k}] ({obstacle.type}): "
                                          "navigate cannot reach it")


def angle_warnings(scenario: ScenarioConfig) -> list[tuple[tuple, str]]:
    """(key path, problem) of every angle that looks like degrees (|angle| > 2 pi)."""
    found = []
    for i, robot in enumerate(scenario.robots):
        found += _degrees(("robots", i, "pose", 2), robot.pose[2])
        if robot.lidar is not None:
            found += _degrees(("robots", i, "lidar", "offset", 2), robot.lidar.offset[2])
    for i, obstacle in enumerate(scenario.obstacles):
        found += _degrees(("obstacles", i, "angle"), getattr(obstacle, "angle", 0.0))
    return found


def _degrees(loc: tuple, angle: float) -> list[tuple[tuple, str]]:
    if abs(angle) <= 2 * math.pi + 1e-9:
        return []
    return [(loc, f"angle {angle:g} rad is more than a full turn: degrees? "
                  f"(radians are meant; {angle:g} degrees is {math.radians(angle):.4g} rad)")]
