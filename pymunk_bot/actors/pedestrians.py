"""Pedestrians walking between their goals with the social force model.

Helbing & Molnar, "Social force model for pedestrian dynamics", Phys. Rev. E 51, 4282 (1995).
Per unit mass, walker a feels
- a driving force (v0 e - v) / tau toward its current goal (e the unit direction, v0 its
  desired speed, tau the relaxation time);
- from every other walker and robot b a repulsion -grad V0 exp(-b / sigma), where b is the
  semi-minor axis of the ellipse through a with foci at b and at b's next step
  (2b = sqrt((|r| + |r - s|)^2 - |s|^2), r = r_a - r_b, s = v_b * STEP_TIME), b less the
  bodies' size beyond NOMINAL_RADIUS each (so a large robot is avoided from farther); forces
  from behind (outside a 200 deg field of view) count at SIGHT_WEIGHT;
- from each wall, obstacle and robot footprint (each shape) within WALL_REACH ranges a
  repulsion U0 / R exp(-d / R) away from its nearest surface (d from the centre, less the
  walker's size beyond NOMINAL_RADIUS);
- optionally a random fluctuation, from the run's seeded generator;
- a small perturbation (by default: a walker's ``perturbation`` sets it, CrowdNav's humans
  have none), at most PERTURBATION (an ORCA walker: ORCA_PERTURBATION) in a random direction,
  drawn afresh each tick from a generator spawned from the crowd's (runs stay deterministic):
  of the wished velocity in the driving term, and of the velocity ORCA chooses (kept within
  ORCA's half-planes). It breaks exact symmetries
  (walkers swapping places across a circle) that otherwise hold every ORCA walker still in the
  middle for ever, as RVO2's own examples perturb theirs;
- a keep-right rule (not in the 1995 paper): KEEP_RIGHT of the social force that holds a
  walker back is turned to its right, so head-on encounters resolve the way people do.
A walker with ``policy: orca`` takes its velocity from ORCA instead (:mod:`.orca`), toward the
same wished velocity. A walker with a ``decision_period`` chooses its velocity that often and
holds it in between (CrowdNav's humans: every 0.25 s); one with ``slow_within`` wishes a speed
that falls in proportion to the distance within that of its goal (CrowdNav's: 1 m). One that does not ``react_to_robot`` leaves robots out of both. Walkers
of one ``group`` share its slowest pace, and each is pulled back toward the group's centre
when it strays farther than GROUP_SPACING per companion (Moussaid et al. 2010's cohesion).
The forces are compiled (numba: :mod:`.social_forces`, :mod:`.surfaces`); the fixed world's
surfaces are read once, when the crowd is made. Each walker is a dynamic disc: contacts push
it (and robots that bump it count a collision); its speed is capped at MAX_SPEED_FACTOR * v0,
and a social-force walker's velocity then closes no gap to another body within the time it
holds it (:mod:`.clearance`: the model is soft at contact, and walkers converging from several
sides would otherwise meet and stay pressed together). ORCA walkers keep CONTACT_MARGIN apart
from each other the same way over the time they hold their velocity (:func:`.orca.closing_limits`:
where ORCA's linear program has no room its answers close gaps); not from robots, which a walker
that does not ``react_to_robot`` must not avoid.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
import pymunk

from pymunk_bot.physics import settings as physics
from pymunk_bot.config.motion import MAX_SPEED_FACTOR
from pymunk_bot.physics.obstacles import Obstacle
from pymunk_bot.actors.body_state import BodyStates
from pymunk_bot.actors.clearance import CONTACT_MARGIN, MAX_CONTACTS, Clearances
from pymunk_bot.actors.orca import MAX_WALL_LINES, Orca, closing_limits
from pymunk_bot.actors.social_forces import NOMINAL_RADIUS, arrivals, cap_speeds, social_forces
from pymunk_bot.actors.surfaces import CellIndex, Surfaces, nearest_walls, wall_forces

WALL_REACH = 5.0  # wall forces are computed out to this many ranges R
PEDESTRIAN_FRICTION = 0.3
# Walkers carry a category bit of their own, so a query leaves them out by its mask (without
# WALKER_CATEGORIES): WALKER_CATEGORY, or in copy r on a shared ground (physics.replica_filter)
# the r-th bit above the copies' bits, which nothing of another copy collides with.
WALKER_CATEGORY = 1 << physics.MAX_REPLICAS
WALKER_CATEGORIES = ((1 << physics.MAX_REPLICAS) - 1) << physics.MAX_REPLICAS
GROUP_SPACING = 0.8  # [m] a companion's share of the group's spread (two walk ~0.8 m apart)
GROUP_PULL = 1.0  # [1/s] wished speed toward the group's centre per metre strayed beyond it
# [m/s] the largest perturbation of a social-force walker's velocity, drawn afresh every tick
# (the default of its ``perturbation``). A thousandth of walking speed: no metric or view shows it.
PERTURBATION = 1e-3
# [m/s] ... of an ORCA walker's. RVO2's examples (Blocks.cc) nudge the preferred velocity by up
# to 1e-4 of a unit speed every step. In a symmetric crossing ORCA's answer sits on a corner of
# the half-planes of the neighbours pressing in, and the wish lies in that corner's normal cone
# (within +-60 deg of straight ahead in a ring of six), so no nudge of the wish moves it: even
# 0.1 m/s left six to twenty walkers crossing a circle, or a square in four groups, jammed for
# 40 s. The answer itself is nudged instead (within the half-planes, actors/orca.py); escaping the
# jam is then a random walk whose pace grows with the nudge: 1 mm/s left 12 and 16 walkers in
# the square jammed for 40 s and the circle took 25 to 36 s; 3 cm/s (2 % of walking speed)
# brings 6 to 20 walkers through either in 5 to 16 s (seeds 0 to 4).
ORCA_PERTURBATION = 0.03


def walker_filter(given: pymunk.ShapeFilter) -> pymunk.ShapeFilter:
    """A walker's filter, from the one its world gave it (a copy's, or WALKER_CATEGORY's)."""
    copy = given.categories & ((1 << physics.MAX_REPLICAS) - 1)
    if not copy or given.categories & WALKER_CATEGORIES:
        return given
    own = copy << physics.MAX_REPLICAS
    return pymunk.ShapeFilter(given.group, own, given.mask & ~(WALKER_CATEGORIES ^ own))


def rejects(a: pymunk.ShapeFilter, b: pymunk.ShapeFilter) -> bool:
    """Whether two shape filters keep their shapes apart (Chipmunk's rule)."""
    return ((a.group != 0 and a.group == b.group) or not a.categories & b.mask
            or not b.categories & a.mask)


def build_pedestrian(space: pymunk.Space, config: Any) -> Obstacle:
    """A walker's body: a dynamic disc that does not spin."""
    body = pymunk.Body(config.mass, math.inf)
    body.position = tuple(config.center)
    shape = pymunk.Circle(body, config.radius)
    shape.friction = PEDESTRIAN_FRICTION
    shape.collision_type = physics.MOVABLE
    shape.filter = pymunk.ShapeFilter(categories=WALKER_CATEGORY)
    space.add(body, shape)
    return Obstacle(config, body, [shape])


class Crowd:
    """Every pedestrian of a world (an actor: ``before_step`` each tick).

    It feels only what its walkers collide with (by their filters), so copies of a world on a
    shared ground (:mod:`pymunk_bot.engine.replicas`) each keep to their own."""

    keeps_to_its_copy = True

    def __init__(self, walkers: Sequence[Obstacle], robots: Sequence, space: pymunk.Space,
                 rng: np.random.Generator) -> None:
        self.walkers = list(walkers)
        self.robots = list(robots)
        self.space = space
        self.rng = rng
        (self._perturbation_rng,) = rng.spawn(1)  # its own stream: the others' stay as they were
        cfg: list[Any] = [w.config for w in self.walkers]
        n = len(cfg)
        self.radius = np.array([c.radius for c in cfg])  # [m]
        base = np.array([c.speed for c in cfg])
        spread = np.array([c.speed_std for c in cfg])
        draws = rng.standard_normal(n)
        # Desired speeds [m/s]: at least 10 % of the nominal one, whatever the draw.
        self.desired = np.maximum(base + spread * draws, 0.1 * base)
        self.tau = np.array([c.relaxation_time for c in cfg])  # [s]
        self.v0 = np.array([c.social_strength for c in cfg])  # [m^2/s^2]
        self.sigma = np.array([c.social_range for c in cfg])  # [m]
        self.u0 = np.array([c.wall_strength for c in cfg])  # [m^2/s^2]
        self.wall_range = np.array([c.wall_range for c in cfg])  # [m]
        self.fluctuation = np.array([c.fluctuation for c in cfg])  # [m/s^2]
        self.reacts = np.array([c.react_to_robot for c in cfg], dtype=bool)
        # The walkers' bodies, then the robots' (read together: the social force needs both).
        self._states = BodyStates([w.body for w in self.walkers]
                                  + [r.body for r in self.robots])
        mine = {shape for w in self.walkers for shape in w.shapes}
        for shape in mine:  # a copy on a shared ground gave them its category: ours instead
            shape.filter = walker_filter(shape.filter)
        names = sorted({c.group for c in cfg if c.group is not None})
        self.groups = [np.array([i for i, c in enumerate(cfg) if c.group == g]) for g in names]
        self.groups = [g for g in self.groups if len(g) > 1]
        for members in self.groups:  # a group walks at its slowest member's pace
            self.desired[members] = self.desired[members].min()
        orca = np.array([c.policy == "orca" for c in cfg], dtype=bool)
        self.orca = Orca(np.flatnonzero(orca), cfg) if orca.any() else None
        self.goals = [np.asarray(c.goals, dtype=float) for c in cfg]
        self.target = [0] * n  # index of the current goal
        self.direction = [1] * n  # +1 forward through the goals, -1 back (pingpong)
        self.done = np.zeros(n, dtype=bool)  # a "once" walker at its last goal
        self._goal_xy = np.array([g[0] for g in self.goals], dtype=float).reshape(-1, 2)
        self._tolerance = np.array([c.goal_tolerance for c in cfg])  # [m]
        self._all_radius = np.concatenate([self.radius, [r.spec.radius for r in self.robots]])
        self._cap = MAX_SPEED_FACTOR * self.desired  # [m/s]
        for i, c in enumerate(cfg):  # a lower cap, where the scenario names one
            if c.max_speed is not None:
                self._cap[i] = min(self._cap[i], c.max_speed)
        self._period = np.array([c.decision_period for c in cfg])  # [s]; 0: every tick
        self._holds = bool(self._period.any())
        self._next_decision = np.zeros(n)  # [s] when each walker chooses anew
        self._held = np.zeros((n, 2))  # [m/s] the velocity each holds until then
        self._slow = np.array([c.slow_within for c in cfg])  # [m]
        self._slows = bool(self._slow.any())
        self._nudge_size = np.array([
            (ORCA_PERTURBATION if c.policy == "orca" else PERTURBATION)
            if c.perturbation is None else c.perturbation for c in cfg])  # [m/s]
        self._wish = self.desired.copy()  # [m/s] the speed wished: 0 once done
        self._no_pull = np.zeros((n, 2))
        self._fluctuates = bool(self.fluctuation.any())
        # Wall forces are felt out to WALL_REACH ranges beyond the walker's body (farther, less
        # than 1 % of the force at contact); ORCA walls bind out to where (d - r) / tau_obst
        # exceeds the speed cap.
        self._wall_reach = WALL_REACH * self.wall_range + self.radius  # [m]
        # reach [m], excess size [m], U0 [m^2/s^2], R [m] of each walker's wall force, radius
        self._walls = np.column_stack([self._wall_reach, self.radius - NOMINAL_RADIUS,
                                       self.u0, self.wall_range, self.radius]).reshape(-1, 5)
        self._clearances = Clearances(n)
        self._step_dt, self._step = math.nan, np.zeros(n)  # see _step_for
        self._mass = np.array([c.mass for c in cfg], dtype=float)  # [kg]
        # the social-force walkers, whose velocity closes no gap within a step (.clearance)
        self._hard_core = ~orca
        self._is_orca = orca
        self._orca_reach = np.zeros(0)  # [m]
        self._orca_apart = Clearances(0)  # the ORCA walkers' pairs' bounds (closing_limits)
        if self.orca is not None:
            agents = self.orca.agents
            self._orca_reach = self.radius[agents] + self._cap[agents] * self.orca.wall_horizon
            self._orca_apart = Clearances(n, int(self.orca.limit.max()) + MAX_CONTACTS)
        # What walkers keep away from: the shapes they collide with, other walkers aside (felt
        # through the social force); the fixed ones read once, the moving ones every tick.
        own_filter = next(iter(mine)).filter if mine else pymunk.ShapeFilter()
        # (Other copies' walkers, robots and crates are kept apart by the filter.)
        felt = [s for s in space.shapes if s not in mine and s.body is not None
                and not s.sensor and not rejects(s.filter, own_filter)]
        fixed = [s for s in felt if s.body is not None and s.body.body_type == pymunk.Body.STATIC]
        robot_bodies = {r.body for r in self.robots}
        self.fixed = Surfaces(fixed, robot_bodies)
        fixed_set = set(fixed)
        self.moving = Surfaces([s for s in felt if s not in fixed_set], robot_bodies)
        self._fixed_poses = self.fixed.poses()
        reach = max([0.0, *self._wall_reach.tolist(), *self._orca_reach.tolist()])
        self._cells = CellIndex(self.fixed.boxes(), reach)

    # ------------------------------------------------------------------ state
    def positions(self) -> np.ndarray:
        """Every walker's position [m], shape (n, 2)."""
        return self._states.read()[:len(self.walkers), :2]

    def velocities(self) -> np.ndarray:
        """Every walker's velocity [m/s], shape (n, 2)."""
        return self._states.read()[:len(self.walkers), 2:]

    def goal_points(self) -> np.ndarray:
        """Every walker's current goal [m], shape (n, 2)."""
        return self._goal_xy.copy()

    # ------------------------------------------------------------------ the tick
    def before_step(self, time: float, dt: float) -> None:
        state = self._states.read()
        n = len(self.walkers)
        # Contiguous copies: the kernels see one array layout whatever the count, so numba
        # compiles each of them once (column slices are 'A' arrays, a single row's are 'C');
        # the walkers' are their leading rows, contiguous too.
        every_xy, every_v = np.ascontiguousarray(state[:, :2]), np.ascontiguousarray(state[:, 2:])
        pos, vel = every_xy[:n], every_v[:n]
        self._advance_goals(pos)
        due = time >= self._next_decision - 1e-9  # who chooses this tick (with no period: all)
        if self._holds and not due.any() and (self._period > 0).all():  # nobody chooses
            self._states.set_velocities(self._held.copy())
            return
        pull = self._cohesion(pos) if self.groups else self._no_pull
        force, pref = np.empty((n, 2)), np.empty((n, 2))
        wish = self._wish
        if self._slows:  # slower within slow_within of the goal
            gap = np.hypot(*(self._goal_xy - pos).T)
            near = np.clip(gap / np.where(self._slow > 0, self._slow, 1.0), 0.0, 1.0)
            wish = np.where(self._slow > 0, wish * near, wish)
        step, clear = self._step_for(dt), self._clearances
        # from everything a walker avoids: walkers, then robots (centres of gravity)
        social_forces(pos, vel, self._goal_xy, wish, pull, self.tau, self.radius,
                      every_xy, every_v, self._all_radius, self.v0, self.sigma,
                      self.reacts, force, pref, clear.reach, clear.near, clear.count)
        poses = self.moving.poses()
        wall_forces(self.fixed, self._fixed_poses, self._cells, pos, self._walls, self.reacts,
                    force, clear)
        wall_forces(self.moving, poses, None, pos, self._walls, self.reacts, force, clear)
        if self._fluctuates:
            force += self.fluctuation[:, None] * self.rng.standard_normal(pos.shape)
        nudge = self._perturbation(n)
        new = vel + (force + nudge / self.tau[:, None]) * dt  # the driving term's wish nudged
        if self.orca is not None:
            # ORCA's answer often sits on a corner of its constraints, which a nudged wish
            # does not move: the velocity it chooses is nudged instead, within them.
            new[self.orca.agents], neighbours = self._orca(pos, vel, pref, state, poses, dt,
                                                           nudge)
        cap_speeds(new, self._cap)
        if self.orca is not None:
            self._keep_orca_apart(pos, new, step, due, neighbours)
        clear.limit(new, step, self._mass, self._hard_core)
        if self._holds:
            new = self._hold(due, new)
        self._states.set_velocities(new)

    def _step_for(self, dt: float) -> np.ndarray:
        """The time [s] each walker holds the velocity it chooses at a tick of ``dt`` [s],
        with the clearances' reach (how far that takes it) set to match (kept while dt is)."""
        if dt != self._step_dt:
            self._step_dt = dt
            self._step = np.where(self._period > 0, self._period, dt)
            self._clearances.reach[:] = self._cap * self._step
        return self._step

    def _hold(self, due: np.ndarray, new: np.ndarray) -> np.ndarray:
        """``new`` [m/s] where a walker's decision is ``due`` (n,); elsewhere the velocity it
        chose last (drift-free: decisions at multiples of its period)."""
        self._held[due] = new[due]
        self._next_decision[due] += self._period[due]
        return self._held.copy()

    def _perturbation(self, n: int) -> np.ndarray:
        """Each walker's nudge [m/s], (n, 2): uniform over the disc of radius its
        ``perturbation`` (by default PERTURBATION, or ORCA_PERTURBATION for an ORCA walker)."""
        draws = self._perturbation_rng.random((n, 2))
        size = self._nudge_size * np.sqrt(draws[:, 0])
        angle = 2.0 * np.pi * draws[:, 1]
        return np.column_stack([size * np.cos(angle), size * np.sin(angle)])

    def _cohesion(self, pos: np.ndarray) -> np.ndarray:
        """Wished velocity [m/s] back toward each walker's group centre, beyond its spread."""
        pull = np.zeros_like(pos)
        for members in self.groups:
            off = pos[members].mean(axis=0) - pos[members]
            dist = np.maximum(np.hypot(off[:, 0], off[:, 1]), 1e-9)
            stray = np.maximum(dist - 0.5 * GROUP_SPACING * (len(members) - 1), 0.0)
            pull[members] = (GROUP_PULL * stray / dist)[:, None] * off
        return pull

    def _orca(self, pos: np.ndarray, vel: np.ndarray, pref: np.ndarray, state: np.ndarray,
              poses: np.ndarray, dt: float,
              nudge: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """Velocities of the ORCA walkers (robots are neighbours or ignored, never walls), and
        whom each took into account (:meth:`.orca.Orca.nearest`); ``state``: every walker's
        and robot's (BodyStates)."""
        assert self.orca is not None
        agents = self.orca.agents
        others = (state[:, :2], state[:, 2:], self._all_radius)
        n, m = len(pos), len(state)
        visible = np.ones((len(agents), m), dtype=bool)
        visible[np.arange(len(agents)), agents] = False
        visible[:, n:] &= self.reacts[agents][:, None]
        at = np.ascontiguousarray(pos[agents])
        hits, count = np.zeros((len(agents), MAX_WALL_LINES, 3)), np.zeros(len(agents), np.int64)
        nearest_walls(self.fixed, self._fixed_poses, self._cells, at, self._orca_reach, hits,
                      count)
        nearest_walls(self.moving, poses, None, at, self._orca_reach, hits, count)
        # an overlap must be undone within the time the velocity is held
        step = np.where(self._period[agents] > 0, self._period[agents], dt)
        neighbours = self.orca.nearest(at, others[0], visible)
        chosen = self.orca.velocities(at, vel[agents], self.radius[agents], others, n,
                                      neighbours, pref[agents], self._cap[agents], step,
                                      (hits, count), nudge[agents])
        return chosen, neighbours

    def _keep_orca_apart(self, pos: np.ndarray, new: np.ndarray, step: np.ndarray,
                         due: np.ndarray, neighbours: tuple[np.ndarray, np.ndarray]) -> None:
        """Where ORCA walkers' velocities ``new`` (n, 2) [m/s] would bring two of them closer
        than CONTACT_MARGIN within the ``step`` (n,) [s] they hold them (ORCA's linear program
        had no room, and its least-violating answers close gaps; or ORCA lets them touch), the
        pair's velocities change by equal and opposite amounts (their masses weigh them) until
        they do not, as clearance.py's speculative contacts do, in place, and do not close on
        the surfaces (and robots, if they react to them) their forces' kernels recorded. Touching
        walkers would meet pymunk's contacts, whose impulses within a tick's substeps push them
        into others.
        Only walkers whose decision is ``due`` (n,) change (others hold theirs).
        A walker that ignores robots must not avoid them: no bound there."""
        assert self.orca is not None
        deciding = self._is_orca & due
        held = np.where(due[:, None], new, self._held) if self._holds else new.copy()
        apart = self._orca_apart
        if closing_limits(self.orca.agents, pos, held, self.radius, step,
                          self._clearances.reach, neighbours, self._is_orca, CONTACT_MARGIN,
                          apart.near, apart.count):
            # what the walkers keep clear of stays binding (walls, obstacles, robots they see)
            apart.add_surfaces(self._clearances, self.orca.agents)
            apart.limit(held, step, self._mass, deciding)
            new[deciding] = held[deciding]

    def _advance_goals(self, pos: np.ndarray) -> None:
        # most ticks: nobody
        for i in arrivals(self._goal_xy, pos, self._tolerance, self.done).tolist():
            walker = self.walkers[i]
            goals, k = self.goals[i], self.target[i]
            config: Any = walker.config
            mode, last = config.mode, len(goals) - 1
            if mode == "loop":
                self.target[i] = (k + 1) % len(goals)
            elif mode == "once":
                if k == last:
                    self.done[i] = True
                    self._wish[i] = 0.0
                else:
                    self.target[i] = k + 1
            else:  # pingpong
                if last == 0:
                    continue
                if not 0 <= k + self.direction[i] <= last:
                    self.direction[i] = -self.direction[i]
                self.target[i] = k + self.direction[i]
            self._goal_xy[i] = goals[self.target[i]]


def make_crowd(world: Any, robots: Sequence[Any], rng: np.random.Generator) -> Crowd | None:
    """The crowd of a world's pedestrians (None when it has none)."""
    walkers = [o for o in world.obstacles if getattr(o.config, "type", "") == "pedestrian"]
    if not walkers:
        return None
    return Crowd(walkers, robots, world.space, rng)
