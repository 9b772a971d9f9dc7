"""The simulation: the clock and the one place where the tick order lives."""
from __future__ import annotations

import math
import numbers
import time as wallclock
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .build import Built, build
from .config import ScenarioConfig, load_scenario
from .config.checks import check_seed
from .expectations import Check, Verdict, evaluate, judge
from .localization.base import LocalizerInputs
from .readings import Observation
from .robot import Robot
from .sensors.lidar import record_all, requests_all
from .sensors.schedule import TIME_TOLERANCE, Schedule, ScheduleArray
from .world import World


def scan_all(caster: Any, due: list[tuple[Any, float]]) -> None:
    """Every due LiDAR (with the time [s] its scan is recorded at) casts: one pass for all."""
    if len(due) > 1:
        record_all(due, caster.cast_many(*requests_all([lidar for lidar, _ in due])))
    elif due:
        lidar, now = due[0]
        lidar.record(now, lidar.true_ranges())


class LocalizationScore:
    """The localizer's estimate against the truth, sampled at a fixed rate."""

    def __init__(self, rate: float) -> None:
        self.schedule = Schedule(rate)
        self.truth: list[np.ndarray] = []
        self.estimate: list[np.ndarray] = []

    def add(self, truth: np.ndarray, estimate: np.ndarray) -> None:
        self.truth.append(np.array(truth, dtype=float))
        self.estimate.append(np.array(estimate, dtype=float))

    def block(self) -> dict[str, float]:
        """rmse, max_error, final_error [m] of the position; heading_rmse [rad]."""
        from .localization.metrics import error_block
        return error_block(np.array(self.truth), np.array(self.estimate))


class Simulation:
    """A scenario in motion. Build it from a file, a dict or a config; reset rebuilds from the seed.

    One tick (:meth:`step`):
    1. controllers whose period has come read their observation and set a command;
    2. actors (moving obstacles, pedestrians) set their motion;
    3. ``substeps`` times: every drive advances and steers its control body, then pymunk steps;
    4. bookkeeping: distance, goals, odometry from the encoders;
    5. sensors whose period has come read the world (every body has moved);
    6. localizers fold in odometry and scans;
    7. metrics that an expectation needs; then the observers (loggers, recorders, views).
    """

    world: World
    _robots: list[Robot]
    _ground: World | None = None  # the shared ground this run is a copy on (replicas), if any
    _replica: int | None = None

    def __init__(self, config: ScenarioConfig, seed: int | None = None,
                 source: str | None = None) -> None:
        self.config = config
        self.source = source or f"scenario '{config.name}'"  # names the file in errors
        self.seed: int = check_seed(config.seed if seed is None else seed) or 0
        self.robots: dict[str, Robot] = {}
        self.observers: list[Callable[["Simulation"], Any]] = []  # run after every step
        self._build()

    @classmethod
    def _on_ground(cls, config: ScenarioConfig, seed: int, source: str | None, ground: World,
                   replica: int) -> "Simulation":
        """Copy ``replica`` of ``config`` on a shared ground (see :mod:`pymunk_bot.replicas`,
        which steps it: its own :meth:`step` would step every copy's physics)."""
        sim = cls.__new__(cls)
        sim._ground, sim._replica = ground, replica
        sim.__init__(config, seed, source)  # type: ignore[misc]
        return sim

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

    def _build(self) -> None:
        world = None
        if self._ground is not None:
            if hasattr(self, "world"):  # a reset: this copy's bodies leave the shared space
                self.world.retire([b for r in self._robots for b in (r.body, r.control)])
            world = World(self.config, self._ground, self._replica)
        built: Built = build(self.config, self.seed, self.source, handles=self.robots,
                             world=world)
        self._built = built
        self.robots.clear()
        self.robots.update(built.robots)  # the same dict and the same handles after a reset
        self.world = built.world
        self.dt = self.config.world.dt
        self.substeps = self.world.substeps
        self.steps = 0
        self.wall_time = 0.0  # [s] spent inside step()
        self._robots = list(self.robots.values())
        self._odometry = [(drive, odometry) for (drive, _), (odometry, _)
                          in zip(built.drive_groups, built.odometry_groups)]
        self._controlled = [i for i, s in enumerate(built.control_schedules) if s is not None]
        self._control = ScheduleArray([s for s in built.control_schedules if s is not None])
        self._lidars = [r.lidar for r in self._robots if r.lidar is not None]
        self._lidar_schedule = ScheduleArray([lidar.schedule for lidar in self._lidars])
        self._sensors = [s for r in self._robots for s in r.sensors
                         if s is not r.lidar and not getattr(s, "passive", False)]
        self._localized = [r for r in self._robots if not getattr(r.localizer, "passive", False)]
        self._mapping = [r for r in self._robots if r.mapper is not None and r.lidar is not None]
        # Robots whose scenario names a localizer are scored against the truth (result JSON's
        # "localization" block), sampled at their controller's rate (10 Hz without one).
        self._scores = {}
        for r in self._robots:
            if "localization" in r.config.model_fields_set:
                r.localization_score = self._scores[r.name] = LocalizationScore(
                    r.controller.rate if r.controller else 10.0)
        for robot in self._localized:  # the first estimate folds in the readings taken at t = 0
            robot.localizer.update(self._localizer_inputs(robot, 0.0))
        self._score(0.0)

    # ------------------------------------------------------------------ state
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
        if self._ground is not None:
            raise RuntimeError("a copy on a shared ground advances with its Replicas.step()")
        started = wallclock.perf_counter()
        self._before_physics()
        propulsion = self._built.propulsion
        propulsion.step(self.dt / self.substeps, self.substeps)
        now = self._bookkeep(propulsion.positions())
        self._read_sensors(now)
        self._after_sensors(now)
        self.wall_time += wallclock.perf_counter() - started
        for observer in self.observers:
            observer(self)

    # The tick's phases, in order (Replicas runs them for many copies around one physics step).
    def _before_physics(self) -> None:
        """Controllers whose period has come set commands; actors set their motion."""
        now = self.steps * self.dt  # self.time, inlined: this runs every tick
        self._run_controllers(now)
        for actor in self.world.actors:
            actor.before_step(now, self.dt)

    def _bookkeep(self, positions: Any) -> float:
        """After the physics: the clock, distance and goals from the robots' new positions,
        odometry from the encoders. Returns the time now [s]."""
        now = self._advance_clock()
        self._built.fleet.advance(positions, now)
        for drive, odometry in self._odometry:
            odometry.update(drive.take_travel())
        return now

    def _advance_clock(self) -> float:
        """One tick more; returns the time now [s]."""
        self.steps += 1
        now = self.world.time = self.steps * self.dt
        return now

    def _after_sensors(self, now: float) -> None:
        """Maps, localizers, localization scores and metrics, once the sensors have read."""
        for robot in self._mapping:
            scan = robot.lidar.latest
            if scan.time == now and robot.mapper.due(now):
                robot.mapper.integrate(robot.pose, scan)
        for robot in self._localized:
            robot.localizer.update(self._localizer_inputs(robot, now))
        if self._scores:
            self._score(now)
        for metrics in self._built.metrics:
            metrics.update(now)

    def run(self, duration: float) -> None:
        """Advance ``duration`` simulated seconds (rounded to whole steps)."""
        if not (isinstance(duration, numbers.Real) and math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be a finite number >= 0 (got {duration!r})")
        for _ in range(round(duration / self.dt)):
            self.step()

    def reset(self, seed: int | None = None) -> None:
        """Rebuild everything from the config (pymunk copies are not bit-exact); ``seed``
        replaces the run's seed. Robot handles and ``robots`` stay valid and see the new state.

        Observers stay attached; those with an ``on_reset(sim)`` method are told.
        """
        if self._ground is not None:
            raise RuntimeError("a copy on a shared ground resets with its "
                               "Replicas.reset(index, seed)")
        self._reset(seed)

    def _reset(self, seed: int | None) -> None:
        if seed is not None:
            self.seed = check_seed(seed) or 0
        self._build()
        for observer in self.observers:
            on_reset = getattr(observer, "on_reset", None)
            if on_reset is not None:
                on_reset(self)

    # ------------------------------------------------------------------ tick parts
    def _run_controllers(self, now: float) -> None:
        # Schedules advance even while a robot is driven by hand, so a controller given back
        # resumes at its own rate instead of catching up on every period it missed.
        robots = self._robots
        for k in self._control.due(now):
            robot = robots[self._controlled[k]]
            if not robot._override:
                command = robot.controller.compute(self.observe(robot))
                robot._drive_group.set_command(robot._di, command)

    def _read_sensors(self, now: float) -> None:
        if self._lidars:
            caster = self.world.ray_caster()
            caster.begin_frame()  # every LiDAR of this tick sees one scene
            scan_all(caster, [(lidar, now) for lidar in self._due_lidars(now)])
        self._read_other_sensors(now)

    def _due_lidars(self, now: float) -> list[Any]:
        """The LiDARs whose scan is due at ``now`` [s] (their schedules advance)."""
        schedule = self._lidar_schedule
        if now + TIME_TOLERANCE < schedule.earliest:  # most ticks (and no LiDAR: never due)
            return []
        return [self._lidars[k] for k in schedule.due(now)]

    def _read_other_sensors(self, now: float) -> None:
        for sensor in self._sensors:
            sensor.update(now)

    def _score(self, now: float) -> None:
        for name, score in self._scores.items():
            if score.schedule.due(now):
                robot = self.robots[name]
                score.add(robot.pose, robot.localizer.pose)

    def _localizer_inputs(self, robot: Robot, now: float) -> LocalizerInputs:
        imu = robot.imu.reading if robot.imu is not None else None
        scan = robot.lidar.latest if robot.lidar is not None else None
        return LocalizerInputs(time=now, odometry=robot.odometry.pose, scan=scan, imu=imu)

    def observe(self, robot: Robot) -> Observation:
        """What ``robot``'s controller knows now."""
        return Observation(
            time=self.time, pose=robot.localizer.pose, odometry=robot.odometry.pose,
            goal=robot.nav_goal, goal_tolerance=robot.goal_tolerance, robot=robot.spec,
            scan=robot.lidar.latest if robot.lidar is not None else None,
            read_extra=robot.readings)

    # ------------------------------------------------------------------ results
    def check_expectations(self) -> list[Check]:
        return evaluate(self.config.expect, self.robots)

    def verdict(self) -> Verdict:
        """The run so far against its expectations and its controllers' status: passed,
        failed, undecided (too short to tell) or unchecked (nothing to check)."""
        statuses = {name: (r.controller.status if r.controller is not None else None,
                           r.controller.message if r.controller is not None else "")
                    for name, r in self.robots.items()}
        return judge(self.config.expect, self.check_expectations(), self.time,
                     self.config.world.duration, statuses, self.dt)

    def _mean_speed(self, robot: Robot) -> float:
        """Up to the goal if reached (not diluted by waiting there), else over the whole run."""
        if robot.time_to_goal is not None and robot.time_to_goal > 0:
            return (robot.distance_to_goal or 0.0) / robot.time_to_goal
        return robot.distance / self.time if self.time > 0 else 0.0

    def result(self) -> dict:
        """The JSON-ready summary of the run so far (see docs/cli.md)."""
        verdict = self.verdict()
        checks = verdict.checks + verdict.undecided
        sim_time = self.time
        robots = {}
        for name, r in self.robots.items():
            pose = r.pose
            odometry = r.odometry.pose
            robots[name] = {
                "pose": [float(pose[0]), float(pose[1]), float(pose[2])],
                "distance": r.distance,
                "collisions": r.collisions,
                "goal_reached": r.goal_reached,
                "time_to_goal": r.time_to_goal,
                "path_length": r.distance,
                "mean_speed": self._mean_speed(r),
                "min_clearance": r.metrics.min_clearance,
                "odometry_pose": [float(v) for v in odometry],
                "odometry_error": float(np.hypot(*(odometry[:2] - pose[:2]))),
                "controller_status": r.controller.status if r.controller is not None else None,
                "controller_message": r.controller.message if r.controller is not None else "",
            }
            if name in self._scores:
                robots[name]["localization"] = self._scores[name].block()
        return {
            "scenario": self.config.name,
            "seed": self.seed,
            "sim_time": sim_time,
            "steps": self.steps,
            "substeps": self.substeps,
            "wall_time": self.wall_time,
            "real_time_factor": sim_time / self.wall_time if self.wall_time > 0 else None,
            "passed": verdict.passed,
            "verdict": verdict.status,
            "undecided": [f"{c.robot}.{c.key}" for c in verdict.undecided],
            "expectations": [c.describe() for c in checks],
            "robots": robots,
        }
