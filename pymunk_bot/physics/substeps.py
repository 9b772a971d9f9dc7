"""Substeps only where contacts can start: each tick's substep count, from the scene.

The scenario's substep count (``config/substeps.py``) keeps every contact shallow and nothing
from tunnelling. It is needed only in ticks where a contact can start or is going on; a tick in
which no two shapes can touch is one ``space.step(dt)``.

A *mover* is a body that moves (a robot, a crate, a pedestrian, a scripted obstacle): its shapes
lie within ``reach`` [m] of its origin, and its origin moves no faster than ``speed`` [m/s]
(robots and pedestrians: their drive's or walk's limit; a crate, which only contacts can speed
up: its speed now). Between two recomputations no contact starts anywhere, so those bounds hold
throughout. The gate keeps the time until which nothing can touch (``clear_until``):

- a mover against the fixed world: its distance to the nearest static shape (a pymunk point
  query) less its reach, over its speed;
- two movers of the same copy: the distance between their origins less both reaches, over
  both speeds.

A tick takes one substep when it ends before ``clear_until``, otherwise the scenario's count;
a test that finds less than ``MIN_CLEAR`` ahead counts as failed. In free space one substep and
many follow the same arc once the motors have settled (to rounding); a motor still ramping
changes speed once in a one-substep tick instead of once per substep. The count is chosen one
tick ahead, because the velocities solved in a tick's last substep move the robots through the
next tick's first: that substep is aimed for the next tick's length. A scene where something is
always near (a crowded fleet) fails the test again and again: each failure waits twice as many
ticks before the next test (at most ``MAX_WAIT``), so the test costs little where it cannot pay.
Bodies moved outside the physics (a teleport) make the next tick take every substep and the
one after it be tested anew.

A tick that takes substeps takes as many as the speeds of the coming two ticks need, not as
many as the drives' top speeds need: the scenario's count is chosen for robots at full speed
(:class:`~pymunk_bot.config.substeps.SubstepNeed`), and most robots of a crowded scene go
slower. The bound is the fastest footprint point any drive can drive within two ticks (its
motors' speeds now, and what they can add by then), or of any body now (a contact may have
just pushed it), and the count never exceeds the scenario's. Contacts are inelastic and the
joints velocity-only, so nothing pushed goes faster than what pushes it.
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numba
import numpy as np
import pymunk
import pymunk.batch as batch
from scipy.spatial import cKDTree

from pymunk_bot.config.substeps import SubstepNeed
from pymunk_bot.physics.static_cells import StaticCells
from pymunk_bot.physics.chipmunk import (CALLS, GET_SPIN, GET_VELOCITY, addresses, get_scalar,
                                         get_vect, read_states)

HORIZON = 2.0  # [s] the farthest ahead one test looks
# [s] how far ahead a k-d tree looks for pairs of movers (fleets of _PAIRS_BY_TREE and more):
# its search radius grows with it, and a crowd has near pairs anyway
PAIR_HORIZON = 0.5
# [s] the least clear time a test must find to grant single substeps: near shapes, where it
# would grant only a tick or two, the full count is cheaper than testing again so soon.
MIN_CLEAR = 0.1
MARGIN = 1e-3  # [m] kept between shapes on top of the bounds (rounding, the contact slop)
MAX_WAIT = 64  # [ticks] the longest wait between tests after failures in a row
_PAIRS_BY_TREE = 48  # movers from which pairs are found with a k-d tree, not all n^2
_IN_ONE_READ = 8  # movers from which every body of the Space is read (one pymunk.batch call)
# (x, y, vx, vy, omega) of every body
_STATE = batch.BodyFields.POSITION | batch.BodyFields.VELOCITY | batch.BodyFields.ANGULAR_VELOCITY


@dataclass
class Mover:
    """A body that moves: ``reach`` [m] from its origin to its farthest shape point; ``speed``
    [m/s] the most its origin moves while nothing touches it (None: its speed now, for a body
    only contacts move); ``copy`` the copy of a shared space it belongs to (None: alone)."""

    body: pymunk.Body
    reach: float
    speed: float | None
    copy: int | None = None

    def __post_init__(self) -> None:
        # Only dynamic bodies meet static shapes (a kinematic one passes through them).
        self.collides_with_static = self.body.body_type == pymunk.Body.DYNAMIC


def reach_of(body: pymunk.Body) -> float:
    """The farthest point of ``body``'s shapes from its origin [m]."""
    reach = 0.0
    for shape in body.shapes:
        if isinstance(shape, pymunk.Circle):
            far = math.hypot(*shape.offset) + shape.radius
        elif isinstance(shape, pymunk.Poly):
            far = max(math.hypot(*v) for v in shape.get_vertices()) + shape.radius
        elif isinstance(shape, pymunk.Segment):
            far = max(math.hypot(*shape.a), math.hypot(*shape.b)) + shape.radius
        else:  # an unknown shape kind: its bounding box about the origin
            bb = shape.bb
            x, y = body.position
            far = max(math.hypot(px - x, py - y) for px in (bb.left, bb.right)
                      for py in (bb.bottom, bb.top))
        reach = max(reach, far)
    return reach


def spin_reach(body: pymunk.Body) -> float:
    """How far [m] from ``body``'s origin the points lie that a turn about its centre of
    gravity moves (a circle's centre, a polygon's or segment's corners), plus the distance
    from the origin to that centre (a control body moves the origin): a turn at omega moves
    no footprint point faster than omega times this, relative to the origin."""
    cx, cy = body.center_of_gravity
    far = 0.0
    for shape in body.shapes:
        if isinstance(shape, pymunk.Circle):
            points = [tuple(shape.offset)]
        elif isinstance(shape, pymunk.Poly):
            points = [tuple(v) for v in shape.get_vertices()]
        elif isinstance(shape, pymunk.Segment):
            points = [tuple(shape.a), tuple(shape.b)]
        else:  # an unknown shape kind: as far as anything of it reaches
            return reach_of(body) + math.hypot(cx, cy)
        far = max([far] + [math.hypot(x - cx, y - cy) for x, y in points])
    return far + math.hypot(cx, cy)


def origin_speeds(vx: np.ndarray, vy: np.ndarray, omega: np.ndarray,
                  offset: np.ndarray) -> np.ndarray:
    """How fast each body's origin moves now [m/s]: its centre of gravity's speed (``vx``,
    ``vy`` [m/s]) plus the turn (``omega`` [rad/s]) of the ``offset`` [m] between the two."""
    return np.hypot(vx, vy) + np.abs(omega) * offset


def near_pairs(xy: np.ndarray, distance: float) -> np.ndarray:
    """Every pair (i < j) of the points ``xy`` (n, 2) [m] within ``distance`` [m] of each
    other, (m, 2); found by a k-d tree, in no particular order."""
    # Unbalanced and not shrunk to its points: the same pairs, the tree built 2.6x faster
    # (10,000 robots on a grid: 0.52 ms against 1.37 ms, the query 1.0-1.1 ms either way).
    tree = cKDTree(xy, balanced_tree=False, compact_nodes=False)
    return tree.query_pairs(distance, output_type="ndarray")


@numba.njit(cache=True)
def pair_gaps(xy: np.ndarray, reach: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """The clearance [m] of each pair (i, j) of discs (centres ``xy`` [m], radii ``reach``
    [m]), MARGIN kept: negative when they may touch now."""
    gaps = np.empty(i.shape[0])
    for k in range(i.shape[0]):
        a, b = i[k], j[k]
        gaps[k] = (math.hypot(xy[a, 0] - xy[b, 0], xy[a, 1] - xy[b, 1]) - reach[a] - reach[b]
                   - MARGIN)
    return gaps


class SubstepGate:
    """Chooses the substep count of each tick (see the module docstring).

    ``full`` is the scenario's count; ``dt`` the tick [s]. ``disturbed()`` says whether bodies
    were moved outside the physics since it was last asked (a teleport). ``need``: the count
    for any speed bound (its ``full`` is ``full``); ``driven(seconds)``: the fastest
    any robot's footprint can be driven within ``seconds`` [m/s] (either None: every tick with
    substeps takes ``full``); ``fixed_version()``: a count that changes when fixed shapes may
    have changed (``World.fixed_version``; None: the Space's shapes compared at every test);
    ``fixed``: the cells of the fixed world a gate before this one on the same Space built
    (kept when the fixed shapes are the same)."""

    def __init__(self, space: pymunk.Space, movers: Sequence[Mover], full: int, dt: float,
                 disturbed: Callable[[], bool], need: SubstepNeed | None = None,
                 driven: Callable[[float], float] | None = None,
                 fixed_version: Callable[[], int] | None = None,
                 fixed: StaticCells | None = None) -> None:
        self.space = space
        self.disturbed = disturbed
        self._driven = driven
        # The highest speed [m/s] that each count from 1 up holds: a count is a bisection.
        self._limits = None if need is None else need.limits
        self.ticks = 0  # ticks counted so far (the gate's own clock: copies reset theirs)
        self.movers = [m for m in movers if m.body.shapes]
        self._bodies = {m.body for m in self.movers}  # shapes of any other body stand still
        # where the fixed shapes are (looked at again when fixed_version() changes)
        self.fixed = (StaticCells(space, self._bodies, fixed_version) if fixed is None
                      else fixed.watching(space, self._bodies, fixed_version))
        # The movers as Chipmunk addresses, read by a compiled loop, and their (x, y, vx, vy, omega)
        self._addresses = addresses([m.body for m in self.movers])
        self._state = np.empty((len(self.movers), 5))
        self._reach = np.array([m.reach for m in self.movers])  # [m]
        # [m] cog to origin
        self._offset = np.array([abs(m.body.center_of_gravity) for m in self.movers])
        # How far the turn of any mover moves its footprint [m / rad].
        self._spin = max([spin_reach(m.body) for m in self.movers], default=0.0)
        # [m/s] each mover's top speed (0: none, a crate: only its speed now counts)
        self._top = np.array([m.speed or 0.0 for m in self.movers])
        self._every = batch.Buffer()  # every body's state (many movers: _graded)
        # Pairs that can touch: of one copy, not both kinematic (kinematic pairs never do).
        self._copy = np.array([-1 if m.copy is None else m.copy for m in self.movers], dtype=np.intp)
        self._dynamic = np.array([m.collides_with_static for m in self.movers], dtype=bool)
        # Each mover's own query filter: the nearest shape through it is never its own
        self._filters = [next(iter(m.body.shapes)).filter for m in self.movers]
        self._pairs = self._meeting(*np.triu_indices(len(self.movers), 1)) \
            if len(self.movers) < _PAIRS_BY_TREE else None  # else found near, with a k-d tree
        self.full = full
        self.dt = dt
        self.clear_until = -math.inf  # [s] no contact can start before this time
        self._planned = full  # the count of the coming tick, chosen in the one before
        self._wait = 0  # ticks left before the next test
        self._failures = 0  # failed tests in a row
        self.single_ticks = 0  # ticks taken in one pymunk step (for results and benchmarks)
        self.steps = 0  # pymunk steps taken (for results and benchmarks)

    def counts(self) -> tuple[int, int]:
        """The substep counts of the coming tick and of the one after it."""
        now = self.ticks * self.dt
        self.ticks += 1
        if self.disturbed():  # the coming tick takes the full count; the next is tested anew
            self.fixed.forget()
            self.clear_until = -math.inf
            self._planned = self.full
            self._wait = 0
        current = self._planned
        self.steps += current
        if current == 1:
            self.single_ticks += 1
            if now + 2.0 * self.dt <= self.clear_until:  # most ticks in open space
                return 1, 1
        elif self._wait > 0:  # most ticks of a crowded scene: substeps, no test
            self._wait -= 1
            self._planned = self._graded()
            return current, self._planned
        if self.full == 1:
            return 1, 1
        end = now + 2.0 * self.dt  # the next tick's end
        planned = 1
        if end > self.clear_until:
            if self._wait > 0:
                self._wait -= 1
                planned = self._graded()
            else:
                until = now + self._clear_for(max(2.0 * self.dt, MIN_CLEAR))
                if now + MIN_CLEAR > until or end > until:
                    # A failed test stops at the first mover that can touch something soon:
                    # the others were not looked at, so its time bounds nothing (kept, it let
                    # a robot that was nearer its wall take single substeps into it).
                    self.clear_until = -math.inf
                    self._failures += 1
                    self._wait = min(MAX_WAIT, 2 ** (self._failures - 1))
                    planned = self._graded()
                else:
                    self.clear_until = until
                    self._failures = 0
        self._planned = planned
        return current, planned

    def counts_apart(self, disturbed: bool, crowded_next: bool, apart: bool) -> tuple[int, int]:
        """:meth:`counts` while robots step apart (physics/apart.py), for the contact Space:
        the coming tick takes what was chosen in the one before (every substep after a
        teleport, ``disturbed``); the next takes what the speeds need if anything moves in the
        contact Space then (``crowded_next``), else one step. ``apart``: robots step apart in
        the coming tick (one more pymunk step). The gate's own test starts afresh when robots
        stop stepping apart."""
        self.ticks += 1
        if disturbed:
            self._planned = self.full
        current = self._planned
        self.steps += current + int(apart)
        if current == 1:
            self.single_ticks += 1
        self._planned = self._graded() if crowded_next else 1
        self.clear_until, self._wait, self._failures = -math.inf, 0, 0
        return current, self._planned

    def _graded(self) -> int:
        """The substeps the next tick needs at the speeds bodies can have within two ticks
        (see the module docstring), at most ``full``."""
        if self._limits is None or self._driven is None:
            return self.full
        # What pushes bodies (the drives), and what is pushed (every body: a pushed one is
        # no faster than its pusher, but a contact may have just sped it up).
        if len(self.movers) < _IN_ONE_READ:  # a few: the movers
            linear, turn = _fastest(CALLS, self._addresses)
            if math.isnan(linear):
                return self.full
        else:  # every body of the Space (other copies' too: they share the count; robots
            # stepping apart are in another and need none: in a 10,000-robot swarm 5 us, where
            # reading every mover took 48 us)
            self._every.clear()
            batch.get_space_bodies(self.space, _STATE, self._every)
            state = np.frombuffer(self._every.float_buf()).reshape(-1, 5)
            linear = float(np.hypot(state[:, 2], state[:, 3]).max(initial=0.0))
            turn = float(np.abs(state[:, 4]).max(initial=0.0))
        speed = max(self._driven(2.0 * self.dt), linear + turn * self._spin)
        if not speed < math.inf:  # NaN: a body thrown out of the world; inf: a drive unknown
            return self.full
        return bisect.bisect_left(self._limits, speed) + 1

    def _clear_for(self, needed: float) -> float:
        """How long [s] (at most HORIZON) no two shapes can touch; stops early, returning
        something below ``needed``, when two movers can touch within it."""
        movers = self.movers
        if not movers:
            return HORIZON
        xy, speeds = self._origins_and_speeds()
        if not math.isfinite(float(xy.sum() + speeds.sum())):
            return 0.0  # a body thrown out of the world: no telling
        clear = self._clear_between_movers(xy, speeds)
        if clear < needed:
            return clear
        # Movers against the fixed world: the cells' bound of how near a fixed shape is, and
        # pymunk's distance where that bound is too short to grant single steps.
        self.fixed.refresh()
        most = self._reach + speeds * clear + MARGIN  # [m] farther shapes change nothing
        dynamic, reach = self._dynamic, self._reach
        until = np.empty(len(movers))
        clearance, within = self.fixed.clearance(xy, most)
        _fixed_times(clearance, reach, speeds, dynamic, until)
        short = until < needed
        if short.any():  # the cells are too coarse here: ask pymunk, as far as a shape may be
            exact = np.empty(len(movers))
            _fixed_times(self.fixed.distances(xy, np.minimum(most, within), short, self._filters),
                         reach, speeds, short, exact)
            until[short] = exact[short]
        clear = min(clear, float(until.min()))
        return max(clear, 0.0)

    def unreachable(self, horizon: float) -> np.ndarray:
        """Per mover: whether neither another mover nor a fixed shape can reach it within
        ``horizon`` [s], each as fast as it can go (the question of which robots may step
        apart: physics/apart.py); none when some body was thrown out of the world."""
        xy, speeds = self._origins_and_speeds()
        clear = np.zeros(len(self.movers), dtype=bool)
        if not math.isfinite(float(xy.sum() + speeds.sum())):
            return clear  # no telling
        clear.fill(True)
        reach = self._reach
        travel = speeds * horizon  # [m] the most each origin moves
        if clear.shape[0] > 1:
            found = near_pairs(xy, 2.0 * float(reach.max() + travel.max()) + MARGIN)
            i, j = self._meeting(found[:, 0], found[:, 1])
            gap = pair_gaps(np.ascontiguousarray(xy), reach, i.astype(np.intp), j.astype(np.intp))
            meet = gap <= travel[i] + travel[j]
            clear[i[meet]] = False
            clear[j[meet]] = False
        # Fixed shapes reach only dynamic movers (inf for the rest, and for those not clear).
        self.fixed.refresh()
        gaps = self.fixed.distances(xy, reach + travel + MARGIN, clear & self._dynamic,
                                    self._filters)
        return clear & (gaps - reach - MARGIN > travel)

    def _meeting(self, i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pairs (i, j) of movers that can touch: of one copy, not both kinematic."""
        meet = (self._copy[i] == self._copy[j]) & (self._dynamic[i] | self._dynamic[j])
        return i[meet], j[meet]

    def _origins_and_speeds(self) -> tuple[np.ndarray, np.ndarray]:
        """The movers' origins (n, 2) [m] and how fast each can go (n,) [m/s]: its speed now
        (see origin_speeds), or its top speed if that is more."""
        rows = self._read_movers()
        xy, motion = rows[:, :2], rows[:, 2:]
        now = origin_speeds(motion[:, 0], motion[:, 1], motion[:, 2], self._offset)
        return xy, np.maximum(now, self._top)

    def _read_movers(self) -> np.ndarray:
        """Every mover's (x, y [m], vx, vy [m/s], omega [rad/s]) now, into a buffer that the
        next call overwrites."""
        read_states(CALLS, self._addresses, self._state)
        return self._state

    def _clear_between_movers(self, xy: np.ndarray, speeds: np.ndarray) -> float:
        """How long [s] no two movers of one copy (origins ``xy`` [m], at most ``speeds``
        [m/s]) can touch (bounding discs), up to HORIZON (PAIR_HORIZON where a k-d tree finds
        the pairs)."""
        n = len(self.movers)
        if n < 2:
            return HORIZON
        reach = self._reach
        horizon = HORIZON
        if self._pairs is not None:
            i, j = self._pairs
        else:
            near = 2.0 * (reach.max() + speeds.max() * PAIR_HORIZON) + MARGIN
            found = near_pairs(xy, near)
            i, j = self._meeting(found[:, 0], found[:, 1])
            horizon = PAIR_HORIZON  # pairs farther apart were not looked at
        # contiguous: one array layout for the kernel (numba compiles it once)
        return _pairs_clear(np.ascontiguousarray(xy), reach, speeds, i.astype(np.intp),
                            j.astype(np.intp), horizon)


@numba.njit(cache=True)
def _fastest(calls: np.ndarray, bodies: np.ndarray) -> tuple[float, float]:
    """The fastest of these bodies' speeds [m/s] (|v| as pymunk's abs(Vec2d)) and spins
    [rad/s]; NaN for both when some body's is NaN."""
    linear = turn = 0.0
    for k in range(bodies.shape[0]):
        vx, vy = get_vect(calls[GET_VELOCITY], bodies[k])
        speed, spin = math.sqrt(vx * vx + vy * vy), abs(get_scalar(calls[GET_SPIN], bodies[k]))
        if speed != speed or spin != spin:
            return math.nan, math.nan
        linear, turn = max(linear, speed), max(turn, spin)
    return linear, turn


@numba.njit(cache=True)
def _fixed_times(gaps: np.ndarray, reach: np.ndarray, speeds: np.ndarray, which: np.ndarray,
                 out: np.ndarray) -> None:
    """``out[k]``: how long [s] mover k (``reach`` [m], at most ``speeds`` [m/s]) cannot touch
    a fixed shape ``gaps[k]`` [m] from its origin (inf: none near), MARGIN kept; inf for the
    movers not ``which``."""
    for k in range(gaps.shape[0]):
        gap = gaps[k] - reach[k] - MARGIN
        speed = speeds[k]
        if not which[k] or gaps[k] == math.inf:
            out[k] = math.inf
        elif speed > 0.0:
            out[k] = gap / speed
        else:
            out[k] = HORIZON if gap > 0.0 else 0.0


@numba.njit(cache=True)
def _pairs_clear(xy: np.ndarray, reach: np.ndarray, speeds: np.ndarray, i: np.ndarray,
                 j: np.ndarray, horizon: float) -> float:
    """How long [s] (at most ``horizon``) none of the pairs (i, j) of discs (centres ``xy``
    [m], radii ``reach`` [m], moving at most ``speeds`` [m/s]) can touch, MARGIN kept."""
    clear = horizon
    gaps = pair_gaps(xy, reach, i, j)
    for k in range(i.shape[0]):
        a, b = i[k], j[k]
        gap = gaps[k]
        closing = speeds[a] + speeds[b]
        t = gap / closing if closing > 0.0 else (horizon if gap > 0.0 else 0.0)
        if not t > 0.0:  # touching now (or NaN: a body thrown out of the world): not clear
            return 0.0
        clear = min(clear, t)
    return clear
