"""The batch: runs that share one pymunk Space and the one place where the tick order lives.

A :class:`~pymunk_bot.engine.simulation.Simulation` of its own is a batch of one; copies of a scenario
sharing a Space (:class:`~pymunk_bot.engine.replicas.Replicas`, the vector env) are a batch of K. The
batch owns what the runs share: the steering of every robot (:class:`Propulsion`), the substep
planners, the ray caster and, for copies, their stacked bookkeeping. Each run owns its clock,
controllers, sensors, localizers and results, and takes part in the tick through its public
phase methods (``act``, ``tick_clock``, ``bookkeep``, ``due_lidars``, ``read``, ``finish``).
"""
from __future__ import annotations

import time as wallclock
from typing import TYPE_CHECKING, Any, Protocol, Sequence

import numpy as np

from pymunk_bot.engine.bookkeeping import Bookkeeping
from pymunk_bot.physics.propulsion import Propulsion
from pymunk_bot.sensors.lidar import Lidar
from pymunk_bot.sensors.lidar_rows import LidarRows
from pymunk_bot.physics.substeps import SubstepGate
from pymunk_bot.physics.apart import RobotsApart
from pymunk_bot.physics.world import World

if TYPE_CHECKING:
    from pymunk_bot.engine.build import Built
    from pymunk_bot.robots.stacking import Stack


class Run(Protocol):
    """What a run in a batch gives the tick (:class:`~pymunk_bot.engine.simulation.Simulation`
    is one): its parts, what it has work for, and its phases in the order :meth:`Batch.step`
    calls them."""

    world: World
    dt: float
    substeps: int
    acts: bool  # work before the physics: controllers, actors, events
    reads: bool  # work after it: sensors other than LiDARs, localizers, maps, metrics
    lidars: list[Lidar]  # in robot order
    robots: dict[str, Any]

    @property
    def built(self) -> "Built": ...
    @property
    def time(self) -> float: ...
    def act(self) -> None: ...
    def tick_clock(self) -> float: ...
    def bookkeep(self) -> float: ...
    def due_lidars(self, now: float) -> list[int]: ...
    def read(self, now: float) -> None: ...
    def finish(self, wall_time: float) -> None: ...


class Batch:
    """``runs`` (in ``ground``'s Space, their robots ``propulsion``'s, run after run), ticked
    as one; ``stack``: the runs' bookkeeping stacked (:mod:`pymunk_bot.robots.stacking`), None
    to keep each run's own; ``before``: the batch these runs were in until one of them was
    rebuilt (what it knew of the fixed world is kept)."""

    def __init__(self, runs: Sequence[Run], ground: World, propulsion: Propulsion,
                 stack: "Stack | None" = None, before: "Batch | None" = None) -> None:
        self.runs = tuple(runs)
        self.ground, self.propulsion, self.stack = ground, propulsion, stack
        # Copies stacked: one bookkeeping pass over every copy's robots (each its copy's time).
        self._stacked = (Bookkeeping(stack.fleet, propulsion.body_addresses, stack.pairs)
                         if stack is not None else None)
        self._count = len(self.runs)
        # A run of its own (no stack): its bookkeeping called straight from the tick.
        self._only = self.runs[0] if self._count == 1 and stack is None else None
        first = self.runs[0]
        self.dt, self.substeps = first.dt, first.substeps
        self._following = 0  # the substep count the worlds were last told of (0: none yet)
        # Which runs have work before and after the physics: a tick skips the rest.
        self.acting = tuple(run for run in self.runs if run.acts)
        self.reading = tuple(run for run in self.runs if run.reads)
        # Every run's LiDARs as rows, each on its robot's row of the propulsion's bodies.
        self.caster = None
        self.lidars: LidarRows | None = None
        if any(run.lidars for run in self.runs):
            self.caster = first.world.ray_caster()
            row_of = {id(body): k for k, body in enumerate(propulsion.bodies)}
            every = [lidar for run in self.runs for lidar in run.lidars]
            self.lidars = LidarRows(every, [row_of[id(lidar.body)] for lidar in every])
            self._first_lidar = np.cumsum([0] + [len(run.lidars) for run in self.runs]).tolist()
        # Substeps where contacts can start (the default; None: every substep every tick).
        self.gate: SubstepGate | None = None
        if first.world.adaptive:
            self.gate = SubstepGate(ground.contact_space,
                                    [m for run in self.runs for m in run.built.movers],
                                    self.substeps, self.dt, ground.take_disturbed, ground.need,
                                    propulsion.fastest_driven, lambda: ground.fixed_version,
                                    before.gate.fixed if before and before.gate else None)
        # Robots that nothing can reach step apart (fleets of SPLIT_FROM robots, in a world
        # of their own: physics/world.py).
        self.split: RobotsApart | None = None
        if self.gate is not None and not propulsion.copies and ground.can_split:
            assert ground.apart_space is not None
            self.split = RobotsApart(ground.apart_space, propulsion.bodies, self.gate, self.dt)
            propulsion.step_apart_in(ground.apart_space)
        # Phase 2, chosen once: a named substep count, substeps where contacts can start, or
        # those and robots stepping apart.
        self._step_physics = (self._physics_every_substep if self.gate is None
                              else self._physics_apart if self.split is not None
                              else self._physics)

    @property
    def single_substep_ticks(self) -> int:
        """Ticks so far that took one pymunk step (0 without adaptive substeps)."""
        return self.gate.single_ticks if self.gate is not None else 0

    @property
    def pymunk_steps(self) -> int | None:
        """pymunk steps taken so far (None without adaptive substeps: ``substeps`` a tick)."""
        return self.gate.steps if self.gate is not None else None

    def step(self) -> None:
        """One tick of ``dt`` for every run:

        1. controllers whose period has come read their observation and set a command; scenario
           events fire; actors (moving obstacles, pedestrians) set their motion;
        2. ``substeps`` times: every drive advances and steers its control body, then pymunk
           steps (in fleets of 2000 robots and more, those nothing can reach are then steered
           once and step once, apart: physics/apart.py);
        3. bookkeeping: each run's clock, distance and goals, odometry from the encoders;
        4. sensors whose period has come read the world (every body has moved): every due LiDAR
           of every run in one cast;
        5. localizers fold in odometry and scans, maps integrate scans, the estimate is scored;
        6. metrics that an expectation needs; then each run's observers (loggers, views).
        """
        started = wallclock.perf_counter()
        for run in self.acting:
            run.act()
        self._step_physics()
        nows = [self._only.bookkeep()] if self._only is not None else self._bookkeep()
        if self.lidars is not None:
            assert self.caster is not None
            self.caster.begin_frame()  # every cast of this tick (on demand too) sees one scene
            self._scan(nows)
        for run in self.reading:
            run.read(run.time)
        share = (wallclock.perf_counter() - started) / self._count
        for run in self.runs:
            run.finish(share)

    def _physics_every_substep(self) -> None:
        """Phase 2 with a named substep count: the drives and pymunk, every substep."""
        self.propulsion.step(self.dt / self.substeps, self.substeps)

    def _physics(self) -> None:
        """Phase 2: the drives and pymunk, with as many substeps as contacts need (one pymunk
        step where no contact can start: physics/substeps.py)."""
        assert self.gate is not None
        substeps, following = self.gate.counts()
        dt = self.dt
        self.propulsion.step(dt / substeps, substeps, dt / following)
        if following != self._following:
            self._substep_after(following)

    def _physics_apart(self) -> None:
        """Phase 2 where robots may step apart (physics/apart.py): the robots nothing can
        reach take one step of the tick in a Space of their own."""
        gate, split, propulsion, dt = self.gate, self.split, self.propulsion, self.dt
        assert gate is not None and split is not None
        world = self.runs[0].world
        if split.apart.any() and split.layout != world.layout:
            split.reset()  # someone gathered the robots (asked for the world's Space)
        if not world.can_split:
            self._physics()
            return
        disturbed = world.take_disturbed()
        if disturbed:  # a teleport: every robot back, decided anew
            split.settle(world, propulsion, np.zeros(split.n, dtype=bool))
            split.reset(disturbed=True)
        apart, following_apart = split.apart, split.next_apart()
        substeps, following = gate.counts_apart(
            disturbed, split.crowded or not following_apart.all(), bool(apart.any()))
        propulsion.step(dt / substeps, substeps, dt / following, (apart, following_apart))
        split.settle(world, propulsion, following_apart)
        if following != self._following:
            self._substep_after(following)

    def _scan(self, nows: list[float]) -> None:
        """Phase 4's LiDARs: every one due, of every run, in one cast (``nows``: each run's
        time [s])."""
        due: list[int] = []
        times: list[float] = []
        for run, now, first in zip(self.runs, nows, self._first_lidar):
            mine = run.due_lidars(now)
            if mine:
                due += [first + k for k in mine]
                times += [now] * len(mine)
        if due:
            assert self.caster is not None and self.lidars is not None
            self.lidars.scan(self.caster, due, times, self.propulsion.pose_array)

    def _substep_after(self, following: int) -> None:
        """Every run's world learns the substep [s] the bodies' velocities now move in (for
        the IMUs): the tick's over ``following``, the next tick's substep count."""
        self._following = following
        for run in self.runs:
            run.world.substep = self.dt / following

    def _bookkeep(self) -> list[float]:
        """Phase 3: every run's clock, then distance, goals and odometry; the runs' times [s]."""
        if self.stack is not None:
            assert self._stacked is not None
            nows = [run.tick_clock() for run in self.runs]
            self._stacked.after_tick(np.repeat(nows, self.stack.per_copy))  # each its copy's time
            return nows
        return [run.bookkeep() for run in self.runs]


def single(run: Run, before: Batch | None = None) -> Batch:
    """The batch of one run, in a world of its own; ``before``: its batch before a reset
    (what it knew of the fixed world stands where the rebuilt world's is the same)."""
    return Batch((run,), run.world, run.built.propulsion, before=before)
