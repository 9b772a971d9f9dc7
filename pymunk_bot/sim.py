"""The simulation: the clock and the one place where the tick order lives."""
from __future__ import annotations

import math
import time as wallclock
from pathlib import Path

import numpy as np

from .config import ScenarioConfig, load_scenario
from .controllers import Observation, controllers
from .errors import ScenarioError
from .expectations import Check, evaluate
from .metrics import RobotMetrics
from .planning.map import MapInfo
from .robot import Robot
from .sensors.attach import attach_sensors
from .world import World


class Simulation:
    """A scenario in motion. Build it from a file or a config; reset rebuilds from the seed.

    One tick (:meth:`step`): controllers whose period has come set wheel commands; the drives
    and physics advance ``substeps`` times; bookkeeping (odometry, distance, goal); sensors
    whose period has come read the world; per-tick metrics.
    """

    def __init__(self, config: ScenarioConfig, seed: int | None = None,
                 source: str | None = None) -> None:
        self.config = config
        self.source = source or f"scenario '{config.name}'"  # names the file in errors
        self.seed = config.seed if seed is None else int(seed)
        self.rng = np.random.default_rng(self.seed)
        world_rng, sensor_rng = self.rng.spawn(2)
        self.world = World(config, world_rng)
        self.dt = config.world.dt
        self.substeps = self.world.substeps
        self.steps = 0
        self.wall_time = 0.0  # [s] spent inside step()
        expect = config.expect
        sensor_rngs = sensor_rng.spawn(len(self.robots))
        self._map: MapInfo | None = None  # built on demand for controllers that need a map
        for robot, rng in zip(self.robots.values(), sensor_rngs):
            attach_sensors(robot, self.world, rng)
            robot.controller = self._make_controller(robot)
            robot.metrics = RobotMetrics(self.world.space, robot,
                                         expect[robot.name].never_enter if robot.name in expect else [])
        self._next_control = {name: 0.0 for name in self.robots}
        self.observers: list = []  # callables f(sim) run after every step (loggers, recorders)

    @classmethod
    def from_file(cls, path: str | Path | None = None, seed: int | None = None) -> "Simulation":
        """Load a scenario file (path or shipped name; None = the built-in default)."""
        return cls(load_scenario(path), seed=seed, source=None if path is None else str(path))

    @classmethod
    def from_dict(cls, data: dict, seed: int | None = None,
                  source: str = "<dict>") -> "Simulation":
        """Build from already-parsed scenario data, with exactly the checks a file gets."""
        from .config import parse_scenario
        return cls(parse_scenario(data, source), seed=seed, source=source)

    # ------------------------------------------------------------------ state
    @property
    def robots(self) -> dict[str, Robot]:
        return self.world.robots

    @property
    def space(self):
        return self.world.space

    @property
    def time(self) -> float:
        """Simulated time [s] (steps * dt, so it never drifts)."""
        return self.steps * self.dt

    # ------------------------------------------------------------------ running
    def step(self) -> None:
        """Advance one physics step of ``dt``."""
        started = wallclock.perf_counter()
        now = self.time
        for robot in self.robots.values():
            self._control(robot, now)
        h = self.dt / self.substeps
        space = self.world.space
        robots = list(self.robots.values())
        for _ in range(self.substeps):
            for robot in robots:
                robot.before_substep(h)
            space.step(h)
        self.steps += 1
        now = self.time
        for robot in robots:
            robot.after_step(now)
        for robot in robots:
            for sensor in robot.sensors:
                sensor.update(now)
            robot.metrics.update(now)
        self.wall_time += wallclock.perf_counter() - started
        for observer in self.observers:
            observer(self)

    def run(self, duration: float) -> None:
        """Advance ``duration`` simulated seconds (rounded to whole steps)."""
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be a finite number >= 0 (got {duration})")
        for _ in range(round(duration / self.dt)):
            self.step()

    def reset(self, seed: int | None = None) -> None:
        """Rebuild everything from the config and seed (pymunk copies are not bit-exact);
        ``seed`` replaces the run's seed.

        Observers stay attached; those with an ``on_reset(sim)`` method are told.
        """
        observers = self.observers
        self.__init__(self.config, self.seed if seed is None else seed, self.source)
        self.observers = observers
        for observer in observers:
            on_reset = getattr(observer, "on_reset", None)
            if on_reset is not None:
                on_reset(self)

    # ------------------------------------------------------------------ control
    def _make_controller(self, robot: Robot):
        config = robot.config.controller
        if config is None:
            return None
        goal = getattr(config, "goal", None)
        if goal is not None:
            robot.nav_goal = tuple(goal)
        index = [r.name for r in self.config.robots].index(robot.name)
        try:
            controller = controllers.get(config.type)(config, robot.spec)
        except ValueError as exc:  # e.g. a user's class refusing its params
            raise ScenarioError(self.source, f"robots[{index}].controller", str(exc)) from None
        if getattr(controller, "needs_map", False):
            # What a real robot's prebuilt map holds: the arena and obstacles as the file says.
            if self._map is None:
                self._map = MapInfo.from_scenario(self.config)
            controller.set_map(self._map)
        return controller

    def observe(self, robot: Robot) -> Observation:
        """What ``robot``'s controller knows now."""
        odometry = robot.odometry.pose
        pose = robot.pose if robot.config.localization == "ground_truth" else odometry
        extra = robot.readings()  # the bumper's reading is built on demand: once, here
        return Observation(
            time=self.time, pose=pose, odometry=odometry, goal=robot.nav_goal,
            goal_tolerance=robot.goal_tolerance, robot=robot.spec,
            scan=robot.lidar.latest if robot.lidar is not None else None,
            bumper=extra["bumper"].touching, extra=extra)

    def _control(self, robot: Robot, now: float) -> None:
        if robot.overridden or robot.controller is None:
            return
        if now + 1e-9 < self._next_control[robot.name]:
            return
        self._next_control[robot.name] += 1.0 / robot.controller.rate
        left, right = robot.controller.compute(self.observe(robot))
        robot.drive.set_wheel_speeds(left, right)

    # ------------------------------------------------------------------ results
    def check_expectations(self) -> list[Check]:
        return evaluate(self.config.expect, self.robots)

    def _mean_speed(self, robot: Robot) -> float:
        """Up to the goal if reached (not diluted by waiting there), else over the whole run."""
        if robot.time_to_goal:
            return robot.distance_to_goal / robot.time_to_goal
        return robot.distance / self.time if self.time > 0 else 0.0

    def result(self) -> dict:
        """The JSON-ready summary of the run so far (see docs/cli.md)."""
        checks = self.check_expectations()
        sim_time = self.time
        robots = {}
        for name, r in self.robots.items():
            pose = r.pose
            odometry_error = float(np.hypot(*(r.odometry.pose[:2] - pose[:2])))
            robots[name] = {
                "pose": [float(pose[0]), float(pose[1]), float(pose[2])],
                "distance": r.distance,
                "collisions": r.collisions,
                "goal_reached": r.goal_reached,
                "time_to_goal": r.time_to_goal,
                "path_length": r.distance,
                "mean_speed": self._mean_speed(r),
                "min_clearance": r.metrics.min_clearance,
                "odometry_pose": [float(v) for v in r.odometry.pose],
                "odometry_error": odometry_error,
                "controller_status": r.controller.status if r.controller is not None else None,
                "controller_message": r.controller.message if r.controller is not None else "",
            }
        return {
            "scenario": self.config.name,
            "seed": self.seed,
            "sim_time": sim_time,
            "steps": self.steps,
            "substeps": self.substeps,
            "wall_time": self.wall_time,
            "real_time_factor": sim_time / self.wall_time if self.wall_time > 0 else None,
            "passed": all(c.passed for c in checks),
            "expectations": [c.describe() for c in checks],
            "robots": robots,
        }
