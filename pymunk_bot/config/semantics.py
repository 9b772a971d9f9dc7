"""Checks that span several keys: names, geometry, where robots start."""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.geometry import plane as geo
from pymunk_bot.config.errors import SemanticError
from pymunk_bot.geometry.footprint import of_robot, transform
from pymunk_bot.config.checks import check as check_more
from pymunk_bot.config.movers import check_mover
from pymunk_bot.config.outlines import (  # noqa: F401 (obstacle_outline, is_round: this module's API before)
    distance_to_obstacle, footprint_hits, footprints_overlap, is_round, obstacle_outline,
    polygon_of,
)
from pymunk_bot.config.schema import PolygonObstacle, RobotConfig, ScenarioConfig, WallObstacle


def _check_polygon(index: int, obstacle: PolygonObstacle) -> None:
    check_footprint_polygon(("obstacles", index, "points"), obstacle.points)


def check_footprint_polygon(loc: tuple, points) -> None:
    """A polygon outline must be simple, with no repeated points and non-zero area."""
    problem = geo.polygon_problem(np.asarray(points, dtype=float))
    if problem is not None:
        raise SemanticError(loc, f"degenerate polygon: {problem}")


def _check_wall(index: int, wall: WallObstacle) -> None:
    if math.dist(wall.start, wall.end) < 1e-9:
        raise SemanticError(("obstacles", index, "end"), "wall has zero length (start == end)")


def _start_neighbours(scenario: ScenarioConfig, feet: list) -> tuple[list[list[int]],
                                                                     list[list[int]]]:
    """For each robot, the obstacles and the earlier robots whose bounding discs its own
    footprint's disc overlaps at the start (ascending): all the start checks need look at.
    A k-d tree finds them, so a swarm's checks grow as n log n, not n^2."""
    n = len(scenario.robots)
    poses = np.array([r.pose for r in scenario.robots], dtype=float).reshape(n, 3)
    local = np.array([f.center for f in feet], dtype=float).reshape(n, 2)
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    with np.errstate(invalid="ignore"):  # a degenerate footprint fails its own check first
        centres = np.column_stack((poses[:, 0] + c * local[:, 0] - s * local[:, 1],
                                   poses[:, 1] + s * local[:, 0] + c * local[:, 1]))
    radii = np.array([f.radius for f in feet], dtype=float)
    valid = np.flatnonzero(np.isfinite(centres).all(axis=1) & np.isfinite(radii))
    robots: list[list[int]] = [[] for _ in range(n)]
    obstacles: list[list[int]] = [[] for _ in range(n)]
    if valid.shape[0] == 0:
        return obstacles, robots
    centres, radii = centres[valid], radii[valid]
    from scipy.spatial import cKDTree  # here: every command checks scenarios, few have swarms

    tree = cKDTree(centres)
    for a, b in sorted(tree.query_pairs(2.0 * float(radii.max()) + 1e-6)):
        if math.dist(centres[a], centres[b]) <= radii[a] + radii[b] + 1e-6:
            i, k = int(valid[max(a, b)]), int(valid[min(a, b)])
            robots[i].append(k)
    for k, obstacle in enumerate(scenario.obstacles):
        if is_round(obstacle):
            centre, reach = np.asarray(obstacle.center, dtype=float), float(obstacle.radius)
        else:
            outline = obstacle_outline(obstacle)
            if outline is None:  # a kind with no outline: every robot is checked against it
                for near in obstacles:
                    near.append(k)
                continue
            centre = outline.mean(axis=0)
            reach = float(np.hypot(*(outline - centre).T).max())
        for j in tree.query_ball_point(centre, reach + float(radii.max()) + 1e-6):
            if math.dist(centres[j], centre) <= reach + radii[j] + 1e-6:
                obstacles[int(valid[j])].append(k)
    for near in robots:
        near.sort()
    return obstacles, robots


def _check_robot_start(index: int, robot: RobotConfig, scenario: ScenarioConfig, feet: list,
                       near_obstacles: list[int], near_robots: list[int]) -> None:
    x, y, _ = robot.pose
    footprint = feet[index]
    geometry = scenario.world.map_geometry()
    if geometry is not None:  # the disc that holds the footprint must start in free space
        from pymunk_bot.config.world_map import disc_problem
        cx, cy = transform(np.array([footprint.center]), robot.pose)[0]
        problem = disc_problem(geometry, float(cx), float(cy), footprint.radius)
        if problem is not None:
            raise SemanticError(("robots", index, "pose"),
                                f"robot of radius {footprint.radius:g} at {problem}")
    else:
        width, height = scenario.world.arena
        if footprint.points is None:
            cx, cy = transform(np.array([footprint.center]), robot.pose)[0]
            r = footprint.radius
            lo, hi = np.array([cx - r, cy - r]), np.array([cx + r, cy + r])
        else:
            outline = footprint.at(robot.pose)
            lo, hi = outline.min(axis=0), outline.max(axis=0)
        if lo[0] < -1e-9 or lo[1] < -1e-9 or hi[0] > width + 1e-9 or hi[1] > height + 1e-9:
            what = (f"robot of radius {footprint.radius:g}" if footprint.points is None
                    else "robot's footprint")
            raise SemanticError(
                ("robots", index, "pose"),
                f"{what} at ({x:g}, {y:g}) is not inside the arena "
                f"[0, {width:g}] x [0, {height:g}]")
    for k in near_obstacles:
        obstacle = scenario.obstacles[k]
        if footprint_hits(footprint, robot.pose, obstacle):
            raise SemanticError(
                ("robots", index, "pose"),
                f"robot starts inside obstacles[{k}] ({obstacle.type})")
    for k in near_robots:
        other = scenario.robots[k]
        if footprints_overlap(footprint, robot.pose, feet[k], other.pose):
            raise SemanticError(("robots", index, "pose"),
                                f"robot overlaps robots[{k}] ({other.name})")


def _check_sideways(index: int, robot: RobotConfig) -> None:
    """Only a holonomic drive takes a lateral speed."""
    vy = getattr(robot.controller, "vy", 0.0)
    if vy:
        from pymunk_bot import plugins
        if not getattr(plugins.drives.get(robot.drive), "holonomic", False):
            raise SemanticError(("robots", index, "controller", "vy"),
                                f"the {robot.drive} drive cannot move sideways: vy must be 0 "
                                f"(got {vy:g}); use drive: omni")


def _check_point_in_arena(loc: tuple, point, scenario: ScenarioConfig) -> None:
    geometry = scenario.world.map_geometry()
    if geometry is not None:
        from pymunk_bot.config.world_map import disc_problem
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
    from pymunk_bot.config.localizer_checks import check_localizer, check_mapping
    try:
        x0, y0, x1, y1 = scenario.world.extent
        check_localizer(robot.localization, robot, has_map=True,  # the scenario is its map
                        arena=(x1 - x0, y1 - y0))
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
        check_mover(i, obstacle, scenario)
    names: dict[str, int] = {}
    with np.errstate(divide="ignore", invalid="ignore"):  # a degenerate one fails its check
        feet = [of_robot(robot) for robot in scenario.robots]
    near_obstacles, near_robots = _start_neighbours(scenario, feet)
    for i, robot in enumerate(scenario.robots):
        if robot.name in names:
            raise SemanticError(("robots", i, "name"),
                                f"duplicate robot name '{robot.name}' (also robots[{names[robot.name]}])")
        names[robot.name] = i
        lidar = robot.lidar
        if lidar is not None and lidar.min_range >= lidar.max_range:
            raise SemanticError(("robots", i, "lidar", "min_range"),
                                f"must be < max_range ({lidar.max_range:g}) (got {lidar.min_range:g})")
        footprint = getattr(robot, "footprint", None)
        if footprint is not None and footprint.type == "polygon":
            check_footprint_polygon(("robots", i, "footprint", "points"), footprint.points)
        _check_robot_start(i, robot, scenario, feet, near_obstacles[i], near_robots[i])
        _check_localization(i, robot, scenario)
        _check_sideways(i, robot)
        if robot.goal is not None:
            _check_point_in_arena(("robots", i, "goal", "position"), robot.goal.position, scenario)
        controller_goal = getattr(robot.controller, "goal", None)
        if controller_goal is not None:
            _check_point_in_arena(("robots", i, "controller", "goal"), controller_goal, scenario)
        if scenario.world.map is not None:  # on a map, waypoints must lie in free space too
            for k, point in enumerate(getattr(robot.controller, "points", None) or ()):
                _check_point_in_arena(("robots", i, "controller", "points", k), point, scenario)
    if not isinstance(scenario.world.substeps, int):  # None or adaptive: computed
        from pymunk_bot.config.schema import MAX_SUBSTEPS
        from pymunk_bot.config.substeps import hardest_shove, required_substeps
        needed = required_substeps(scenario)
        shove = hardest_shove(scenario)
        if shove is not None and shove.substeps > MAX_SUBSTEPS:
            raise SemanticError(
                ("obstacles", shove.obstacle, "mass"),
                f"{shove.mass:g} kg is too light to be pushed by a {shove.pusher_mass:g} kg body "
                f"at {shove.speed:.3g} m/s with world.dt = {scenario.world.dt:.4g} s: the solver "
                f"would need {shove.substeps} substeps (at most {MAX_SUBSTEPS}) to keep it out of "
                f"walls; make it heavier, or lower world.dt or the speed")
        if needed > MAX_SUBSTEPS:
            fastest = max(range(len(scenario.robots)),
                          key=lambda i: scenario.robots[i].top_speed())
            raise SemanticError(
                ("robots", fastest, "max_wheel_speed" if scenario.robots[fastest].drive == "diff"
                 else "max_speed"),
                f"too fast for world.dt = {scenario.world.dt:g} s: it would need {needed} "
                f"substeps (at most {MAX_SUBSTEPS}) not to tunnel; lower world.dt or the speed")
    for name, expectation in scenario.expect.items():
        if name not in names:
            from pymunk_bot.config.messages import did_you_mean
            raise SemanticError(("expect", name),
                                f"no robot named '{name}'{did_you_mean(name, names)}")
        needs_goal = expectation.goal_reached is not None or expectation.within is not None
        if needs_goal and scenario.robots[names[name]].goal is None:
            raise SemanticError(("expect", name), "expects a goal but the robot has no 'goal'")
    check_more(scenario)
