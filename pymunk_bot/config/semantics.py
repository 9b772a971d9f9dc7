"""Checks that span several keys: names, geometry, where robots start."""
from __future__ import annotations

import math

import numpy as np

from .. import geometry as geo
from .schema import (
    BoxObstacle, CircleObstacle, PolygonObstacle, RobotConfig, ScenarioConfig, WallObstacle,
)


class SemanticError(Exception):
    """A problem at a key path (a tuple, as pydantic's locations are)."""

    def __init__(self, loc: tuple, problem: str) -> None:
        super().__init__(problem)
        self.loc = loc
        self.problem = problem


def obstacle_outline(obstacle) -> np.ndarray | None:
    """Polygon outline of an obstacle [m], or None for circles. A plugin's obstacle kind gives
    its own through an ``outline()`` method."""
    if hasattr(obstacle, "outline"):
        return np.asarray(obstacle.outline(), dtype=float)
    if isinstance(obstacle, BoxObstacle):
        return geo.box_corners(obstacle.center, obstacle.size, obstacle.angle)
    if isinstance(obstacle, WallObstacle):
        return geo.wall_corners(obstacle.start, obstacle.end, obstacle.thickness)
    if isinstance(obstacle, PolygonObstacle):
        return np.asarray(obstacle.points, dtype=float)
    return None


def distance_to_obstacle(point, obstacle) -> float:
    """Distance from a point to an obstacle's surface (0 inside)."""
    if isinstance(obstacle, CircleObstacle):
        return max(0.0, math.dist(point, obstacle.center) - obstacle.radius)
    return geo.distance_to_polygon(point, polygon_of(obstacle))


def polygon_of(obstacle) -> np.ndarray:
    """The outline of an obstacle that is not a circle (TypeError if it has none)."""
    outline = obstacle_outline(obstacle)
    if outline is None:
        raise TypeError(f"obstacle type '{obstacle.type}' has no outline: give its config "
                        "model an outline() method")
    return outline


def _check_polygon(index: int, obstacle: PolygonObstacle) -> None:
    points = np.asarray(obstacle.points, dtype=float)
    loc = ("obstacles", index, "points")
    for i in range(len(points)):
        if np.allclose(points[i], points[(i + 1) % len(points)]):
            raise SemanticError(loc, f"degenerate polygon: point {i} repeats its neighbour")
    if not geo.is_simple_polygon(points):
        raise SemanticError(loc, "degenerate polygon: edges cross each other")
    if abs(geo.signed_area(points)) < 1e-9:
        raise SemanticError(loc, "degenerate polygon: zero area")


def _check_wall(index: int, wall: WallObstacle) -> None:
    if math.dist(wall.start, wall.end) < 1e-9:
        raise SemanticError(("obstacles", index, "end"), "wall has zero length (start == end)")


def _check_robot_start(index: int, robot: RobotConfig, scenario: ScenarioConfig) -> None:
    x, y, _ = robot.pose
    r = robot.radius
    geometry = scenario.world.map_geometry()
    if geometry is not None:
        from .world_map import disc_problem
        problem = disc_problem(geometry, x, y, r)
        if problem is not None:
            raise SemanticError(("robots", index, "pose"), f"robot of radius {r:g} at {problem}")
    else:
        width, height = scenario.world.arena
        if not (r <= x <= width - r and r <= y <= height - r):
            raise SemanticError(
                ("robots", index, "pose"),
                f"robot of radius {r:g} at ({x:g}, {y:g}) is not inside the arena "
                f"[0, {width:g}] x [0, {height:g}]")
    for k, obstacle in enumerate(scenario.obstacles):
        if distance_to_obstacle((x, y), obstacle) < r - 1e-9:
            raise SemanticError(
                ("robots", index, "pose"),
                f"robot starts inside obstacles[{k}] ({obstacle.type})")
    for k, other in enumerate(scenario.robots[:index]):
        if math.dist((x, y), other.pose[:2]) < r + other.radius - 1e-9:
            raise SemanticError(("robots", index, "pose"), f"robot overlaps robots[{k}] ({other.name})")


def _check_point_in_arena(loc: tuple, point, scenario: ScenarioConfig) -> None:
    geometry = scenario.world.map_geometry()
    if geometry is not None:
        from .world_map import disc_problem
        problem = disc_problem(geometry, float(point[0]), float(point[1]), 0.0)
        if problem is not None:
            raise SemanticError(loc, problem)
        return
    width, height = scenario.world.arena
    if not (0 <= point[0] <= width and 0 <= point[1] <= height):
        raise SemanticError(loc, f"({point[0]:g}, {point[1]:g}) is outside the arena "
                                 f"[0, {width:g}] x [0, {height:g}]")


def _check_localization(index: int, robot: RobotConfig, scenario: ScenarioConfig) -> None:
    """A localizer or mapping the robot cannot run (no LiDAR, too large a map) is bad input."""
    from ..localization.checks import check_localizer, check_mapping
    try:
        check_localizer(robot.localization, robot, has_map=True)  # the scenario is its map
    except ValueError as exc:
        raise SemanticError(("robots", index, "localization"), str(exc)) from None
    if robot.mapping is not None:
        try:
            check_mapping(robot.mapping, scenario.world.arena)
        except ValueError as exc:
            raise SemanticError(("robots", index, "mapping"), str(exc)) from None


def check(scenario: ScenarioConfig) -> None:
    """Raise SemanticError for the first problem found."""
    for i, obstacle in enumerate(scenario.obstacles):
        if isinstance(obstacle, PolygonObstacle):
            _check_polygon(i, obstacle)
        elif isinstance(obstacle, WallObstacle):
            _check_wall(i, obstacle)
    names: dict[str, int] = {}
    for i, robot in enumerate(scenario.robots):
        if robot.name in names:
            raise SemanticError(("robots", i, "name"),
                                f"duplicate robot name '{robot.name}' (also robots[{names[robot.name]}])")
        names[robot.name] = i
        lidar = robot.lidar
        if lidar is not None and lidar.min_range >= lidar.max_range:
            raise SemanticError(("robots", i, "lidar", "min_range"),
                                f"must be < max_range ({lidar.max_range:g}) (got {lidar.min_range:g})")
        _check_robot_start(i, robot, scenario)
        _check_localization(i, robot, scenario)
        if robot.goal is not None:
            _check_point_in_arena(("robots", i, "goal", "position"), robot.goal.position, scenario)
        controller_goal = getattr(robot.controller, "goal", None)
        if controller_goal is not None:
            _check_point_in_arena(("robots", i, "controller", "goal"), controller_goal, scenario)
        if scenario.world.map is not None:  # on a map, waypoints must lie in free space too
            for k, point in enumerate(getattr(robot.controller, "points", None) or ()):
                _check_point_in_arena(("robots", i, "controller", "points", k), point, scenario)
    if scenario.world.substeps is None:
        from .schema import MAX_SUBSTEPS
        from .substeps import required_substeps
        needed = required_substeps(scenario)
        if needed > MAX_SUBSTEPS:
            fastest = max(range(len(scenario.robots)),
                          key=lambda i: scenario.robots[i].top_speed())
            raise SemanticError(
                ("robots", fastest, "max_wheel_speed"),
                f"too fast for world.dt = {scenario.world.dt:g} s: it would need {needed} "
                f"substeps (at most {MAX_SUBSTEPS}) not to tunnel; lower world.dt or the speed")
    for name, expectation in scenario.expect.items():
        if name not in names:
            from .messages import did_you_mean
            raise SemanticError(("expect", name),
                                f"no robot named '{name}'{did_you_mean(name, names)}")
        needs_goal = expectation.goal_reached is not None or expectation.within is not None
        if needs_goal and scenario.robots[names[name]].goal is None:
            raise SemanticError(("expect", name), "expects a goal but the robot has no 'goal'")
    from .checks import check as check_more; check_more(scenario)  # noqa: E702 (issue 9)
