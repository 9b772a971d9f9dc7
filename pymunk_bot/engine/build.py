"""The build layer: a validated config and a seed -> the world, robots, drives, sensors,
controllers and localizers of one run. ``Simulation`` keeps only the clock and the tick order.

Random streams: one ``numpy.random.Generator`` from the seed, spawned down the tree in a fixed
order (world -> per-robot odometry; sensors -> per robot -> per sensor kind; then controllers
and localizers), so adding a sensor to one robot never changes another's draws.
"""
from __future__ import annotations

import gc
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Iterator

import numpy as np
import pymunk

from pymunk_bot.physics import settings as physics
from pymunk_bot.actors import make_actors
from pymunk_bot.config.metric_bounds import bounds_of
from pymunk_bot.config.schema import ScenarioConfig
from pymunk_bot.config.substeps import mover_speed
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.geometry.footprint import of_robot
from pymunk_bot.localization.base import LocalizerContext
from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.config.localization import LOCALIZER_MAP_RESOLUTION
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.outcomes.metrics import RobotMetrics
from pymunk_bot.outcomes.navigation.recorder import NavMetrics
from pymunk_bot.physics.obstacles import footprint_shapes
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.plugins import controllers, drives, localizers
from pymunk_bot.plugins import odometry as odometry_kinds
from pymunk_bot.physics.propulsion import Propulsion
from pymunk_bot.physics.substeps import Mover, reach_of
from pymunk_bot.robots.readings import RobotSpec
from pymunk_bot.robots.robot import Fleet, Robot
from pymunk_bot.robots.rows import OWN, Rows
from pymunk_bot.sensors.attach import attach_sensors
from pymunk_bot.sensors.schedule import Schedule
from pymunk_bot.physics.world import World



@dataclass
class Built:
    """Everything one run is made of."""

    world: World
    robots: dict[str, Robot]
    fleet: Fleet
    drive_groups: list[tuple[Any, list[int]]]  # each group with its robots' indices
    odometry_groups: list[tuple[Any, list[int]]]
    propulsion: Propulsion
    control_schedules: list[Schedule | None]
    maps: "MapSource"
    metrics: list[RobotMetrics] = field(default_factory=list)  # the robots that measure any
    movers: list[Mover] = field(default_factory=list)  # what moves (adaptive substeps)


class MapSource:
    """What a robot may know in advance: the scenario's map, built once on first request (and
    kept by a run's resets: build's ``maps``), with the likelihood fields localizers read."""

    def __init__(self, config: ScenarioConfig) -> None:
        self.config = config
        self._info: MapInfo | None = None
        self._grid: OccupancyGrid | None = None
        self._fields: dict[float, LikelihoodField] = {}  # by max_dist [m]

    def info(self) -> MapInfo:
        """Arena and obstacles as geometry (for planners)."""
        if self._info is None:
            self._info = MapInfo.from_scenario(self.config)
        return self._info

    def grid(self) -> OccupancyGrid:
        """The static geometry as an occupancy grid (for localizers)."""
        if self._grid is None:
            from pymunk_bot.maps.rasterize import grid_from_map
            self._grid = grid_from_map(self.info().without_movable(), LOCALIZER_MAP_RESOLUTION)
        return self._grid

    def likelihood(self, max_dist: float) -> LikelihoodField:
        """The likelihood field of :meth:`grid` capped at ``max_dist`` [m] (read only, so
        every localizer on this map shares it; building it was half of an MCL run's reset)."""
        field = self._fields.get(max_dist)
        if field is None:
            field = self._fields[max_dist] = LikelihoodField(self.grid(), max_dist)
        return field


def build(config: ScenarioConfig, seed: int, source: str,
          handles: dict[str, Robot] | None = None, world: World | None = None,
          rows: Rows = OWN, maps: MapSource | None = None) -> Built:
    """Build a run; ``handles`` (from an earlier build) are rebound instead of made anew.
    ``world``: a world already made for it (a copy on a shared ground), else a new one.
    ``rows``: where its groups keep their per-robot state (a copy's rows of the arrays its
    copies share: :mod:`pymunk_bot.robots.rows`), else arrays of their own. ``maps``: what an
    earlier build of this config knew of its map (a reset), else found anew."""
    with _collector_paused():
        return _build(config, seed, source, handles, world, rows, maps)


@contextmanager
def _collector_paused() -> Iterator[None]:
    """Python's cyclic garbage collector off while a run is built: building 10,000 robots makes
    millions of objects that all live on, and the collector would scan the growing heap again
    and again (a third of the build's CPU time). What the build drops is collected after."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _build(config: ScenarioConfig, seed: int, source: str, handles: dict[str, Robot] | None,
           world: World | None, rows: Rows, known: MapSource | None) -> Built:
    """:func:`build`, the collector paused."""
    rng = np.random.default_rng(seed)
    world_rng, sensor_rng = rng.spawn(2)
    (mind_rng,) = rng.spawn(1)  # controllers and localizers
    (actor_rng,) = rng.spawn(1)  # pedestrians (spawned last: earlier streams stay as they were)
    world = World(config) if world is None else world
    fleet = Fleet(list(config.robots), rows.of_fleet())
    fleet.extent = config.world.extent  # goals set from code must lie in the arena
    n = len(config.robots)
    robots: dict[str, Robot] = {}
    by_drive: dict[str, list[int]] = {}
    for i, rc in enumerate(config.robots):
        by_drive.setdefault(rc.drive, []).append(i)
    drive_groups = [(_make_drive(name, [config.robots[i] for i in idx], rows), idx)
                    for name, idx in by_drive.items()]
    handles = handles or {}
    for group, idx in drive_groups:
        for j, i in enumerate(idx):
            rc = config.robots[i]
            robot = handles.get(rc.name) or Robot(rc.name)
            robot.bind(fleet, i, group, j)
            robot.on_moved = world.disturb
            _make_body(robot, rc, world, group, j, group_id=i + 1)
            robot.drive = group.handle(j)
            robots[rc.name] = robot
    robots = {rc.name: robots[rc.name] for rc in config.robots}  # scenario order
    ordered = list(robots.values())
    odometry_rngs = world_rng.spawn(n)
    odometry_groups = []
    for group, idx in drive_groups:
        odometry = _make_odometry(group, [odometry_rngs[i] for i in idx], rows)
        for j, i in enumerate(idx):
            ordered[i].odometry = odometry.handle(j)
        odometry_groups.append((odometry, idx))
    world.actors.extend(make_actors(world, ordered, actor_rng))
    for robot, child in zip(ordered, sensor_rng.spawn(n)):
        attach_sensors(robot, world, child)
    maps = known if known is not None and known.config is config else MapSource(config)
    schedules: list[Schedule | None] = []
    mind_rngs = mind_rng.spawn(n)
    for index, (robot, child) in enumerate(zip(ordered, mind_rngs)):
        # The first child is kept for controllers (none draws yet), so the localizers'
        # streams stay where they are when one starts to.
        _, localizer_rng = child.spawn(2)
        robot.controller = _make_controller(robot, index, maps, source)
        schedules.append(None if robot.controller is None else Schedule(robot.controller.rate))
        robot.localizer = _make_localizer(robot, index, maps, source, localizer_rng, config)
        if robot.config.mapping is not None:
            from pymunk_bot.localization.mapping import OccupancyMapper
            x0, y0, x1, y1 = config.world.extent  # the arena, or a map's extent in its frame
            m = robot.config.mapping.margin
            robot.mapper = OccupancyMapper(robot.config.mapping, ((x0 - m, y0 - m), (x1 + m, y1 + m)))
        elif hasattr(robot.localizer, "grid"):  # slam builds its own map
            robot.mapper = robot.localizer
    built = Built(world, robots, fleet, drive_groups, odometry_groups,
                  Propulsion(world.contact_space, [r.body for r in ordered],
                             [r.control for r in ordered], [(g, idx) for g, idx in drive_groups]),
                  schedules, maps)
    crowd = any(getattr(o, "type", "") == "pedestrian" for o in config.obstacles)
    for robot in ordered:
        expectation = config.expect.get(robot.name)
        never_enter = expectation.never_enter if expectation else []
        clearance = expectation is not None and expectation.min_clearance is not None
        # Metrics that query the world see all of it (a robot stepping apart too).
        robot.metrics = RobotMetrics(
            world.space if never_enter or clearance else world.contact_space, robot,
            never_enter, track_clearance=clearance)
        if crowd or (expectation is not None and bounds_of(expectation)):  # navmetrics/
            robot.metrics.navigation = NavMetrics(world, robot, ordered, config, maps)
        if robot.metrics.active or robot.metrics.navigation is not None:
            built.metrics.append(robot.metrics)
    if world.adaptive:
        built.movers = _movers(world, ordered)
    return built


def _movers(world: World, robots: list[Robot]) -> list[Mover]:
    """Every body that moves, with how far its shapes reach and how fast it can go: a robot as
    fast as its drive allows, a pedestrian or scripted obstacle as its config allows, a crate
    (None) only as fast as contacts push it."""
    movers = [Mover(r.body, reach_of(r.body), r.config.top_speed(), world.replica)
              for r in robots]
    for obstacle in world.obstacles:
        body = obstacle.body
        if body.body_type == pymunk.Body.STATIC:
            continue
        speed = mover_speed(obstacle.config)
        pushed_only = body.body_type == pymunk.Body.DYNAMIC and speed == 0.0
        movers.append(Mover(body, reach_of(body), None if pushed_only else speed, world.replica))
    return movers


def _make_drive(name: str, configs: list[Any], rows: Rows) -> Any:
    """The drive group of kind ``name`` for these robots; one that names its per-robot fields
    (``ROWS``) keeps them on ``rows``."""
    kind = drives.get(name)
    if getattr(kind, "ROWS", ()):
        return kind(configs, rows.of_drive(name))
    return kind(configs)


def _make_odometry(group: Any, rngs: list[np.random.Generator], rows: Rows) -> Any:
    """The drive group's odometry: the one registered under its drive's name, else its own.
    That of a drive whose fields are rows (``ROWS``) keeps its own on ``rows`` too."""
    kind = group.configs[0].drive
    if kind not in odometry_kinds:
        return group.make_odometry(rngs)
    if getattr(type(group), "ROWS", ()):
        return odometry_kinds.get(kind)(group, rngs, rows=rows.of_odometry(kind))
    return odometry_kinds.get(kind)(group, rngs)


def _make_body(robot: Robot, rc: Any, world: World, group: Any, j: int, group_id: int) -> None:
    """The robot's dynamic body and shape, and the control body and joints that pull it."""
    robot.config = rc
    robot.spec = group.spec(j) if hasattr(group, "spec") else RobotSpec(
        rc.name, of_robot(rc).bounding_radius, getattr(rc, "track_width", 0.0), rc.top_speed(),
        getattr(rc, "max_accel", 0.0), drive=rc.drive,
        footprint=of_robot(rc))
    x, y, theta = rc.pose
    if getattr(rc, "footprint", None) is None:
        body = pymunk.Body(rc.mass, pymunk.moment_for_circle(rc.mass, 0, rc.radius))
        shapes: list[pymunk.Shape] = [pymunk.Circle(body, rc.radius)]
    else:  # mass spread over the footprint: the centre of gravity lands on its centroid
        body = pymunk.Body()
        shapes = footprint_shapes(body, of_robot(rc), rc.mass)
    body.position = (x, y)
    body.angle = theta
    for shape in shapes:
        shape.friction = rc.friction
        shape.collision_type = physics.ROBOT
        # The group keeps the robot's own LiDAR from seeing its own body.
        shape.filter = world.shape_filter(group_id)
    shape = shapes[0]
    control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    control.position = (x, y)
    control.angle = theta
    force, torque = group.joint_limits(j, rc.mass, body.moment)
    pivot = pymunk.PivotJoint(control, body, (0, 0), (0, 0))
    pivot.max_bias = 0.0  # velocity-only: a blocked robot never winds up
    pivot.max_force = force
    gear = pymunk.GearJoint(control, body, 0.0, 1.0)
    gear.max_bias = 0.0
    gear.max_force = torque
    world.contact_space.add(body, *shapes, control, pivot, gear)
    robot.body, robot.shape, robot.control = body, shape, control
    robot.shapes = shapes
    for piece in shapes:
        world.count_contacts(piece, robot.count_collision)


def _make_controller(robot: Robot, index: int, maps: MapSource, source: str) -> Any:
    config = robot.config.controller
    if config is None:
        return None
    goal = getattr(config, "goal", None)
    robot.nav_goal = tuple(goal) if goal is not None else robot.goal
    try:
        controller = controllers.get(config.type)(config, robot.spec)
    except ValueError as exc:  # e.g. a user's class refusing its params
        raise ScenarioError(source, f"robots[{index}].controller", str(exc)) from None
    if getattr(controller, "needs_map", False):
        # What a real robot's prebuilt map holds: the arena and obstacles as the file says.
        controller.set_map(maps.info())
    return controller


def _make_localizer(robot: Robot, index: int, maps: MapSource, source: str,
                    rng: np.random.Generator, config: ScenarioConfig) -> Any:
    section = robot.config.localization
    factory = localizers.get(section.type)
    needs_map = bool(getattr(factory, "needs_map", False))
    lidar = robot.sensor("lidar")
    context = LocalizerContext(
        robot=robot.spec, start_pose=np.array(robot.config.pose, dtype=float), rng=rng,
        arena=config.world.arena, map=maps.grid() if needs_map else None,
        likelihood=maps.likelihood if needs_map else None,
        lidar_offset=lidar.offset if lidar is not None else (0.0, 0.0, 0.0),
        origin=config.world.extent[:2])
    kwargs: dict[str, Any] = {}
    if section.type == "ground_truth":
        kwargs["truth"] = lambda: robot.pose
    elif section.type == "odometry":
        kwargs["odometry"] = robot.odometry
    try:
        return factory(section, context, **kwargs)
    except ValueError as exc:
        raise ScenarioError(source, f"robots[{index}].localization", str(exc)) from None
