"""The simulation: the clock and the one place where the tick order lives."""
from __future__ import annotations

import math
import numbers
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pymunk

from pymunk_bot.engine.batch import Batch, single
from pymunk_bot.engine.build import Built, MapSource, build
from pymunk_bot.config import ScenarioConfig, load_scenario
from pymunk_bot.config.checks import check_seed
from pymunk_bot.engine.events import EventSchedule
from pymunk_bot.outcomes.expectations import Check, Verdict, evaluate, judge
from pymunk_bot.localization.base import LocalizerInputs
from pymunk_bot.localization.score import LocalizationScore
from pymunk_bot.engine.observing import Observer, observe
from pymunk_bot.engine.bookkeeping import Bookkeeping
from pymunk_bot.robots.readings import Observation
from pymunk_bot.robots.robot import Robot, RobotsByName
from pymunk_bot.robots.rows import OWN, Rows
from pymunk_bot.sensors.schedule import TIME_TOLERANCE, ScheduleArray
from pymunk_bot.physics.world import World


class Simulation:
    """A scenario in motion. Build it from a file, a dict or a config; reset rebuilds from the seed.

    One tick (:meth:`step`) runs in the order :meth:`Batch.step <pymunk_bot.engine.batch.Batch.step>`
    gives: a run of its own is a batch of one.

    ``ground``, ``replica`` and ``rows``: this run is copy ``replica`` of its scenario on a
    ground shared with other copies, its robots' state in its rows of the arrays they share
    (:class:`~pymunk_bot.engine.replicas.Replicas` builds, steps and resets these).
    """

    world: World
    _robots: list[Robot]
    _batch: Batch | None = None  # its batch (none for a copy on a shared ground)
    _maps: MapSource | None = None  # its map and what was derived from it (engine/build.py)

    def __init__(self, config: ScenarioConfig, seed: int | None = None,
                 source: str | None = None, *, ground: World | None = None,
                 replica: int | None = None, rows: Rows = OWN) -> None:
        self.config = config
        self.source = source or f"scenario '{config.name}'"  # names the file in errors
        self.seed: int = check_seed(config.seed if seed is None else seed) or 0
        self.robots: dict[str, Robot] = RobotsByName()  # a missing name lists the robots
        self.observers: list[Callable[["Simulation"], Any]] = []  # run after every step
        self._ground, self._replica, self._rows = ground, replica, rows
        self._build()

    @classmethod
    def from_file(cls, path: str | Path | None = None, seed: int | None = None) -> "Simulation":
        """Load a scenario file (path or shipped name; None = the built-in default)."""
        return cls(load_scenario(path), seed=seed, source=None if path is None else str(path))

    @classmethod
    def from_dict(cls, data: dict, seed: int | None = None,
                  source: str = "<dict>") -> "Simulation":
        """Build from already-parsed scenario data, with exactly the checks a file gets."""
        from pymunk_bot.config import parse_scenario
        return cls(parse_scenario(data, source), seed=seed, source=source)

    def _build(self) -> None:
        world = None
        if self._ground is not None:
            if hasattr(self, "world"):  # a reset: this copy's bodies leave the shared space
                self.world.retire([b for r in self._robots for b in (r.body, r.control)])
            world = World(self.config, self._ground, self._replica)
        built: Built = build(self.config, self.seed, self.source, handles=self.robots,
                             world=world, rows=self._rows, maps=self._maps)
        self._built = built
        self._maps = built.maps  # a reset keeps what it knew of the map
        self.robots.clear()
        self.robots.update(built.robots)  # the same dict and the same handles after a reset
        self.world = built.world
        self.dt = self.config.world.dt
        self.substeps = self.world.substeps
        self.steps = 0
        self.wall_time = 0.0  # [s] spent inside step()
        self._robots = list(self.robots.values())
        self._bookkeeping = Bookkeeping(
            built.fleet, built.propulsion.body_addresses,
            [(drive, odometry) for (drive, _), (odometry, _)
             in zip(built.drive_groups, built.odometry_groups)])
        self._controlled = [i for i, s in enumerate(built.control_schedules) if s is not None]
        self._control = ScheduleArray([s for s in built.control_schedules if s is not None])
        self._observer = Observer(self._robots, built.fleet, built.odometry_groups)
        # Its LiDARs, in robot order (the batch scans them as rows: sensors/lidar_rows.py).
        self.lidars = [lidar for lidar in (r.sensor("lidar") for r in self._robots)
                       if lidar is not None]
        self._lidar_schedule = ScheduleArray([lidar.schedule for lidar in self.lidars])
        self._sensors = [s for r in self._robots for s in r.sensors
                         if s is not r.sensor("lidar") and not getattr(s, "passive", False)]
        self._localized = [r for r in self._robots if not getattr(r.localizer, "passive", False)]
        self._mapping = [r for r in self._robots
                         if r.mapper is not None and r.sensor("lidar") is not None]
        self._events = EventSchedule(self.config.events)
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
        # What this run does around the physics, so a tick skips the phases it has no work in.
        self.acts = bool(self._controlled or self.world.actors or self.config.events)
        self.reads = bool(self._sensors or self._mapping or self._localized or self._scores
                          or built.metrics)
        # A copy on a shared ground ticks in its Replicas' batch, never in one of its own.
        self._batch = (None if self._ground is not None
                       else single(self, self._batch))
        # What step() calls: its batch's tick (or, for a copy, the error above)
        self._tick = self._batch.step if self._batch is not None else self._own_batch

    # ------------------------------------------------------------------ state
    @property
    def space(self) -> pymunk.Space:
        """The pymunk Space of this run (shared with other copies on a shared ground), with
        every body in it: in fleets where robots step apart (docs/physics.md), asking for it
        brings them back, and the rest of the run keeps them in it."""
        return self.world.space

    @property
    def time(self) -> float:
        """Simulated time [s] (steps * dt, so it never drifts)."""
        return self.steps * self.dt

    @property
    def single_substep_ticks(self) -> int:
        """Ticks so far (since the last reset) that took one pymunk step: no contact could
        start in them, or everything went slowly enough for one step to hold contacts
        (adaptive substeps, a run of its own; 0 otherwise)."""
        return self._batch.single_substep_ticks if self._batch is not None else 0

    @property
    def pymunk_steps(self) -> int:
        """pymunk steps taken so far (since the last reset): ``substeps`` per tick with a named
        count; with adaptive substeps, one per tick where no contact can start and as many as
        the speeds need elsewhere (of a run of its own)."""
        steps = self._batch.pymunk_steps if self._batch is not None else None
        return self.steps * self.substeps if steps is None else steps

    def __repr__(self) -> str:
        return (f"Simulation({self.config.name!r}, seed={self.seed}, t={self.time:.3f} s of "
                f"{self.config.world.duration:g} s, dt={self.dt:.4g} s x {self.substeps} "
                f"substeps, robots: {', '.join(self.robots)})")

    @property
    def built(self) -> Built:
        """What this run is made of (world, fleet, drive and odometry groups, propulsion):
        read it, do not rebuild it (:meth:`reset` does)."""
        return self._built

    # ------------------------------------------------------------------ running
    def step(self) -> None:
        """Advance one physics step of ``dt``."""
        self._tick()

    def _own_batch(self) -> Batch:
        """This run's batch of one (a copy on a shared ground has none: its Replicas ticks it)."""
        if self._batch is None:
            raise RuntimeError("a copy on a shared ground advances with its Replicas.step()")
        return self._batch

    # The tick's phases, in the order Batch.step runs them.
    def act(self) -> None:
        """Controllers whose period has come set commands; events fire; actors set their
        motion."""
        soon = self.steps * self.dt + TIME_TOLERANCE  # self.time, inlined: this runs every tick
        actors = self.world.actors
        # Most ticks of a run without actors: no event and no controller due, nothing to do.
        if not actors and soon < self._control.earliest and soon < self._events.next_at:
            return
        now = self.steps * self.dt
        if self._events.due(now):  # scenario events (teleports: engine/events.py)
            self._events.fire(now, self.robots)
        self._run_controllers(now)
        for actor in actors:
            actor.before_step(now, self.dt)

    def bookkeep(self) -> float:
        """After the physics: the clock, distance and goals from the robots' bodies, odometry
        from the encoders (engine/bookkeeping.py). Returns the time now [s]."""
        now = self.tick_clock()
        self._bookkeeping.after_tick(now)
        return now

    def tick_clock(self) -> float:
        """One tick more; returns the time now [s]."""
        self.steps += 1
        now = self.world.time = self.steps * self.dt
        return now

    def read(self, now: float) -> None:
        """After the LiDARs: the other sensors, then maps, localizers, scores and metrics."""
        for sensor in self._sensors:
            sensor.update(now)
        self._after_sensors(now)

    def finish(self, wall_time: float) -> None:
        """The tick is over: it took this run ``wall_time`` [s]; the observers see it."""
        self.wall_time += wall_time
        for observer in self.observers:
            observer(self)

    def _after_sensors(self, now: float) -> None:
        """Maps, localizers, localization scores and metrics, once the sensors have read."""
        for robot in self._mapping:
            if robot.lidar.latest_time == now and robot.mapper.due(now):
                robot.mapper.integrate(robot.pose, robot.lidar.latest)
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
        for _ in range(round(duration / self.dt)):  # read anew each tick: an observer may reset
            self._tick()

    def exclude_from_wall_time(self, seconds: float) -> None:
        """Take ``seconds`` [s] spent inside steps on something else than the steps (numba
        compiling a kernel on its first call) out of ``wall_time`` and the real-time factor."""
        self.wall_time = max(self.wall_time - seconds, 0.0)

    def attach(self, observer: Any) -> None:
        """Add ``observer`` (called after every step) once: if it has ``on_reset(sim)``, that
        is called now, so it starts from the present state, and again after every reset."""
        on_reset = getattr(observer, "on_reset", None)
        if on_reset is not None:
            on_reset(self)
        if observer not in self.observers:
            self.observers.append(observer)

    def detach(self, observer: Any) -> None:
        """Stop calling ``observer`` after every step (nothing if it was not attached)."""
        if observer in self.observers:
            self.observers.remove(observer)

    def reset(self, seed: int | None = None) -> None:
        """Rebuild everything from the config (pymunk copies are not bit-exact); ``seed``
        replaces the run's seed. Robot handles and ``robots`` stay valid and see the new state.

        Observers stay attached; those with an ``on_reset(sim)`` method are told.
        """
        if self._ground is not None:
            raise RuntimeError("a copy on a shared ground resets with its "
                               "Replicas.reset(index, seed)")
        self._reset(seed)

    def reset_copy(self, seed: int | None = None) -> None:
        """:meth:`reset` of a copy on a shared ground (what ``Replicas.reset`` calls, which
        then rebuilds the steering and stacks of every copy)."""
        if self._ground is None:
            raise RuntimeError("only a copy on a shared ground resets with reset_copy")
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
        due = self._control.due(now)
        if not due:
            return
        fleet = self._built.fleet  # who drives each robot: no handle is read to ask
        controlled, by_hand, held = self._controlled, fleet.by_hand, fleet.holds_constant
        # Not those driven by hand, nor constant controllers whose command the drive holds.
        indices = [i for i in map(controlled.__getitem__, due) if not (by_hand[i] or held[i])]
        if not indices:
            return
        robots, observes, constant = self._robots, fleet.observes, fleet.constant
        # A controller that reads no observation (constant commands) gets None: none is built.
        watching = [i for i in indices if observes[i]]
        observations = self._observer.observe_many(watching, now) if watching else iter(())
        for i in indices:
            robot = robots[i]
            robot.follow(robot.controller.compute(next(observations) if observes[i] else None))
            held[i] = constant[i]

    def due_lidars(self, now: float) -> list[int]:
        """Which of ``lidars`` have a scan due at ``now`` [s] (their schedules advance)."""
        schedule = self._lidar_schedule
        if now + TIME_TOLERANCE < schedule.earliest:  # most ticks (and no LiDAR: never due)
            return []
        return schedule.due(now)

    def _score(self, now: float) -> None:
        for name, score in self._scores.items():
            if score.schedule.due(now):
                robot = self.robots[name]
                score.add(robot.pose, robot.localizer.pose)

    def _localizer_inputs(self, robot: Robot, now: float) -> LocalizerInputs:
        imu, lidar = robot.sensor("imu"), robot.sensor("lidar")
        imu = imu.reading if imu is not None else None
        scan = lidar.latest if lidar is not None else None
        return LocalizerInputs(time=now, odometry=robot.odometry.pose, scan=scan, imu=imu)

    def observe(self, robot: Robot) -> Observation:
        """What ``robot``'s controller knows now."""
        return observe(robot, self.time)

    # ------------------------------------------------------------------ results
    def check_expectations(self) -> list[Check]:
        """Every expectation of the scenario against the run so far, one Check each."""
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
            if r.metrics.navigation is not None:  # a crowd, or expect bounds (navmetrics/)
                robots[name]["metrics"] = r.metrics.navigation.values()
        return {
            "scenario": self.config.name,
            "seed": self.seed,
            "sim_time": sim_time,
            "steps": self.steps,
            "substeps": self.substeps,
            "single_step_ticks": self.single_substep_ticks,
            "pymunk_steps": self.pymunk_steps,
            "wall_time": self.wall_time,
            "real_time_factor": sim_time / self.wall_time if self.wall_time > 0 else None,
            "passed": verdict.passed,
            "verdict": verdict.status,
            "undecided": [f"{c.robot}.{c.key}" for c in verdict.undecided],
            "expectations": [c.describe() for c in checks],
            "robots": robots,
        }
