"""Every substep: each drive's body twist -> its robot's kinematic control body velocity.

The tank pattern (docs/physics.md): the control body's velocity is what the joints pull the robot
toward. pymunk integrates positions before it solves velocities, so the velocity set now moves
the robot during the next substep: we aim it along the chord of that substep's arc, at the
heading the robot will have half a substep after this one, scaled by sinc(omega h / 2), which
keeps a robot in free space exactly on its commanded arc.

With many robots the bodies are read and written in one call each through ``pymunk.batch``;
with few, property access per robot is cheaper. Both paths call the same compiled formulas
(:mod:`pymunk_bot.physics.steering`), so a robot gets the same floats on either.

A drive group whose motors have settled on their commands is *held* for the whole step
instead (with many robots, once every group has settled: one batch read and write for all): a
turning robot's control body spins at omega about its own centre and the pivot joint's anchor
on it sits where that spin gives the same chord velocity (the anchor is fixed in the control
body's frame, because the wanted velocity turns with the robot), so the substeps run without
Python in between. The control body's heading is matched to the robot's
at the start of each step, as the per-substep aim does every substep; only a robot knocked off
its heading by a contact within a step follows the held heading for the rest of that step.
"""
from __future__ import annotations

import math
from typing import Any, Iterable, Sequence

import numpy as np
import pymunk
import pymunk.batch as batch

from pymunk_bot.physics.bodies import BodyRows, get_angle, get_position, get_spin, handles
from pymunk_bot.robots.drives.base import SMALL_GROUP
from pymunk_bot.robots.stacking import DriveUnits
from pymunk_bot.physics.steering import aim, aim_rows, anchor, hold_rows
from pymunk_bot.physics.substeps import spin_reach

# A held robot's anchor is |u| / |omega| from the control body's centre; farther than this
# [m] (an almost straight path) it is aimed substep by substep instead.
_MAX_ANCHOR = 1e6

# pymunk routes every attribute write on a body through a Python __setattr__ (a typing
# aid); calling the property setters directly skips it, halving the cost of a write.
_SET_VELOCITY = vars(pymunk.Body)["velocity"].fset
_SET_SPIN = vars(pymunk.Body)["angular_velocity"].fset
_SET_ANGLE = vars(pymunk.Body)["angle"].fset

_READ = batch.BodyFields.ANGLE | batch.BodyFields.VELOCITY | batch.BodyFields.ANGULAR_VELOCITY
_POSE = batch.BodyFields.POSITION | batch.BodyFields.ANGLE
_WRITE = batch.BodyFields.VELOCITY | batch.BodyFields.ANGULAR_VELOCITY

# From this many robots aimed in one substep, the per-robot path reads, aims and writes them as
# rows (one pymunk.batch read and write for all) rather than by property access one by one.
ROWS_AIM = 6

_UNKNOWN = (math.nan,) * 3  # a control body's last written twist, when it was written as rows


def _each_twist(members: list[int], twists: tuple[Any, Any, Any]
                ) -> Iterable[tuple[int, tuple[float, float, float]]]:
    """Each robot of ``members`` with its twist as floats (robot by robot, numpy's scalars
    cost more than floats; one robot's without building lists)."""
    ux, uy, omega = twists
    if len(members) == 1:
        return ((members[0], (ux.item(0), uy.item(0), omega.item(0))),)
    if isinstance(ux, np.ndarray):
        ux, uy, omega = ux.tolist(), uy.tolist(), omega.tolist()
    return zip(members, zip(ux, uy, omega))


class Propulsion:
    """Steers every robot's control body; ``groups`` pairs each drive group with the indices
    (into ``bodies``) of its robots, in the group's order.

    Copies of a scenario sharing a space (:mod:`pymunk_bot.engine.replicas`) pass ``copies``:
    ``groups`` then holds each copy's groups, and each copy is steered as its own simulation
    would steer it, robot by robot. ``stacked``: the same robots in fewer, larger groups (see
    :mod:`pymunk_bot.robots.stacking`), each copy's group some rows of one of them; the copies' groups
    are then advanced through these, one call for all copies."""

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body],
                 controls: Sequence[pymunk.Body], groups: Sequence[tuple[Any, Sequence[int]]],
                 stacked: Sequence[tuple[Any, Sequence[int], Sequence[int]]] | None = None,
                 copies: bool = False) -> None:
        self.space = space
        self.bodies, self.controls = list(bodies), list(controls)
        self._handles, self._control_handles = handles(self.bodies), handles(self.controls)
        # The bodies as rows of batch reads: of the contact Space, and of the one robots
        # nothing can reach step in (physics/apart.py), once they may.
        self.rows = BodyRows(space, self.bodies, self.controls)
        self._h, self._h_next = np.empty(1), np.empty(1)  # one step for every robot aimed
        self.groups = [(g, np.asarray(idx, dtype=np.intp)) for g, idx in groups]
        # What the per-robot path advances: each group, or each stacked group with the first
        # row of each copy's part (``stacked`` gives (group, robot indices, part starts)).
        self._drives = ([DriveUnits(g, list(idx), np.asarray(starts, dtype=np.intp))
                         for g, idx, starts in stacked] if stacked
                        else [DriveUnits(g, idx.tolist(), None) for g, idx in self.groups])
        self.n = len(self.bodies)
        self.batched = self.n >= SMALL_GROUP and not copies
        # Body origin -> centre of gravity [m] (a car's pose point is its rear axle): pymunk
        # moves the centre straight within a substep, so the origin's path needs a correction.
        self.cog = np.array([tuple(b.center_of_gravity) for b in self.bodies]).reshape(-1, 2)
        self._cog = [(float(x), float(y)) for x, y in self.cog.tolist()]  # the same, as floats
        self._everyone = np.arange(self.n, dtype=np.intp)
        spin = np.array([spin_reach(b) for b in self.bodies])  # [m / rad]
        # Each group's rows (copies' groups: each stacked group's, one call for all copies).
        self._spins = [(drives.group, spin[drives.member_rows]) for drives in self._drives]
        self._anchors = np.zeros((self.n, 2))  # [m] the held anchors (batched)
        self._xy = np.zeros((self.n, 2))  # [m] positions read one by one (positions)
        self._holding = False  # the fleet is held as a whole (batched)
        self._held_twists = np.full((self.n, 3), np.nan)  # the twists held (batched; NaN: none)
        self._changed = np.zeros(self.n, dtype=np.bool_)  # whose twist the last hold changed
        # What each control body was last given: a write (a pymunk call) is skipped when the
        # new value is the same, as it is while a robot drives straight at a steady speed.
        self._given: list[tuple[float, float, float]] = [(math.nan,) * 3] * self.n
        self.pivots = [next(c for c in control.constraints if isinstance(c, pymunk.PivotJoint))
                       for control in self.controls]
        self._held: list[tuple[float, float, float] | None] = [None] * self.n  # twist held
        self._anchored = [False] * self.n  # the pivot's anchor is off the control body's centre

    def fastest_driven(self, seconds: float) -> float:
        """The fastest any robot's footprint can be driven within ``seconds`` [m/s] (see
        ``DriveGroup.fastest``)."""
        return max([group.fastest(spin, seconds) for group, spin in self._spins], default=0.0)

    def step(self, h: float, substeps: int, h_next: float | None = None,
             apart: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        """Advance the drives and the physics by ``substeps`` substeps of ``h`` [s];
        ``h_next``: the next tick's substep [s], when it differs (the velocities solved in this
        tick's last substep move the robots through the next tick's first, so that substep is
        aimed for it). ``apart``: which robots step apart (one step of the whole tick, in the
        second Space) in this tick and in the next, two boolean rows (batched only)."""
        space = self.space
        h_last = h if h_next is None else h_next
        if apart is not None:
            self._step_split(h, substeps, h_last, *apart)
            return
        if self.batched:
            self._step_batched(h, substeps, h_last)
            return
        # Groups (copies' parts) settled before the step keep their twists through it: held,
        # and coasted (not in a tick before another substep length: every substep is aimed).
        steady: list[tuple[int, tuple[float, float, float]]] = []  # held, yet aimed each substep
        loose: list[tuple[DriveUnits, list[int]]] = []
        hold = self._hold
        for drives in self._drives:
            moving = drives.every_unit
            if h_last == h:
                members, twists, moving = drives.coast_settled(moving, h, substeps)
                if twists is not None:  # each held, or aimed every substep (``steady``)
                    for k, twist in _each_twist(members, twists):
                        if not hold(k, twist, h):
                            steady.append((k, twist))
            if moving:
                loose.append((drives, moving))
        if not (steady or loose):  # every robot held: nothing to do between substeps
            for _ in range(substeps):
                space.step(h)
            return
        for sub in range(substeps):
            after = h_last if sub == substeps - 1 else h  # the substep this aim moves
            if sub:
                for k, twist in steady:
                    self._aim(k, twist, h, after)
            for drives, units in loose:
                rows, members, member_rows = drives.rows(units)
                self._aim_members(members, member_rows, drives.advance(h, rows), h, after)
            space.step(h)
            left = substeps - 1 - sub
            if loose and left > 1 and h_last == h:  # motors settled now: held for the rest
                still: list[tuple[DriveUnits, list[int]]] = []
                for drives, units in loose:
                    members, twists, moving = drives.coast_settled(units, h, left)
                    if twists is not None:
                        for k, twist in _each_twist(members, twists):
                            if not hold(k, twist, h):
                                steady.append((k, twist))
                    if moving:
                        still.append((drives, moving))
                loose = still

    def _aim_members(self, members: list[int], member_rows: np.ndarray,
                     twists: tuple[Any, Any, Any], h: float, h_next: float) -> None:
        """:meth:`_aim` for these robots (twists in their order; ``member_rows``: ``members``
        as an array): one by one when few, else as rows (the same compiled formula: the same
        floats)."""
        if len(members) < ROWS_AIM:
            for k, twist in _each_twist(members, twists):
                self._aim(k, twist, h, h_next)
            return
        if any(self._anchored):  # from holding: the anchors back to the centres
            for k in members:
                if self._anchored[k]:
                    self.pivots[k].anchor_a = (0.0, 0.0)
                    self._anchored[k] = False
        if len(members) == self.n:  # what _aim keeps per robot, for all at once
            self._held, self._given = [None] * self.n, [_UNKNOWN] * self.n
        else:
            for k in members:
                self._held[k] = None
                self._given[k] = _UNKNOWN
        self._aim_rows(member_rows, twists, h, h_next)

    def _step_batched(self, h: float, substeps: int, h_last: float) -> None:
        """``step`` for many robots: held as a whole fleet when every group has settled,
        else aimed every substep (the last for ``h_last``); bodies read and written through
        ``pymunk.batch``."""
        space = self.space
        if h_last == h and all(group.settled() for group, _ in self.groups):
            twists = self._gather(lambda group: group.coast(h, substeps))
            if self._hold_all(twists, h):
                for _ in range(substeps):
                    space.step(h)
                return
            self._release_anchors()
            for _ in range(substeps):  # an almost straight arc: aimed, at constant twists
                self._aim_all(twists, h, h)
                space.step(h)
            return
        self._release_anchors()
        for sub in range(substeps):
            self.substep(h, h_last if sub == substeps - 1 else h)
            space.step(h)

    def _step_split(self, h: float, substeps: int, h_last: float, apart: np.ndarray,
                    apart_next: np.ndarray) -> None:
        """``step`` with the robots ``apart`` (a boolean row) stepping apart: every drive
        advances each substep, as in any tick; the others are aimed substep by substep and
        step in the contact Space, then those apart are aimed once, for the whole tick, and
        their Space takes one step of it. Each robot's last aim is for the step it takes
        first in the next tick: the tick when it steps apart then (``apart_next``), else
        ``h_last``."""
        self._release_anchors()
        dt = h * substeps
        near, away = np.flatnonzero(~apart), np.flatnonzero(apart)
        first_next = np.where(apart_next, dt, h_last)  # [s] each robot's next step
        contact, other = self.rows.spaces
        for sub in range(substeps):
            twists = self._gather(lambda group: group.advance(h))
            ux, uy, omega = twists
            if near.size:
                self._aim_rows(near, (ux[near], uy[near], omega[near]), h,
                               first_next[near] if sub == substeps - 1 else h, slice(0, 1))
            contact.step(h)
        if away.size:  # their motors advanced the whole tick, in substeps, as the others'
            self._aim_rows(away, (ux[away], uy[away], omega[away]), dt, first_next[away],
                           slice(1, 2))
            other.step(dt)

    def _gather(self, twists_of: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ux, uy, omega) of every robot, each group's from ``twists_of(group)``."""
        ux, uy, omega = np.empty(self.n), np.empty(self.n), np.empty(self.n)
        for group, idx in self.groups:
            ux[idx], uy[idx], omega[idx] = twists_of(group)
        return ux, uy, omega

    def _hold_all(self, twists: tuple[np.ndarray, np.ndarray, np.ndarray], h: float) -> bool:
        """The batched :meth:`_hold`: every robot held for the step (a turning one by its
        pivot's anchor, a straight one aimed once), in one read and one write; False (nothing
        written) if some robot's anchor would lie beyond _MAX_ANCHOR."""
        ux, uy, omega = twists
        state = self._read_state()
        out, anchors = self.rows.held_out, self._anchors
        out[:] = state
        self._h[0] = h
        if not hold_rows(state, self.rows.robot, self.rows.control, ux, uy, omega, self._h,
                         self.cog, _MAX_ANCHOR, anchors, out, self._held_twists, self._changed):
            return False
        for k in np.flatnonzero(self._changed).tolist():  # anchors are no batch field:
            turning = bool(omega[k] != 0.0)  # written when a twist changes, or held ones let go
            if turning or self._anchored[k]:
                self.pivots[k].anchor_a = (float(anchors[k, 0]), float(anchors[k, 1]))
                self._anchored[k] = turning
        self._holding = True
        self.rows.write(_READ, held=True)
        return True

    def _release_anchors(self) -> None:
        """Back from holding: every pivot anchor to its control body's centre."""
        if self._holding:
            for k in np.flatnonzero(self._anchored).tolist():
                self.pivots[k].anchor_a = (0.0, 0.0)
                self._anchored[k] = False
            self._held_twists.fill(np.nan)
            self._holding = False

    def adopt(self, previous: "Propulsion") -> None:
        """Take over what ``previous`` knew of the bodies both steer (anchors, last writes),
        as a fleet of copies rebuilds its Propulsion after one copy's reset."""
        known = {id(body): j for j, body in enumerate(previous.bodies)}
        for k, body in enumerate(self.bodies):
            j = known.get(id(body))
            if j is not None:
                self._given[k], self._held[k], self._anchored[k] = previous.steering_of(j)
        if self.batched and any(self._anchored):
            self._holding = True  # so a release lets them go
            self._held_twists.fill(np.nan)  # every anchor written anew

    def steering_of(self, k: int) -> tuple[tuple[float, float, float],
                                           tuple[float, float, float] | None, bool]:
        """What this Propulsion knows of robot ``k``'s control body: the twist last written,
        the twist held (None: none) and whether its pivot's anchor is off the centre."""
        return self._given[k], self._held[k], self._anchored[k]

    def step_apart_in(self, apart: pymunk.Space) -> None:
        """Robots may step apart, in ``apart`` (physics/apart.py): its bodies are read too
        (once: a plan made again keeps its propulsion)."""
        if apart not in self.rows.spaces:
            self.rows.add(apart)

    def relocated(self) -> None:
        """Bodies moved between the Spaces: where each sits is looked up at the next read."""
        self.rows.relocated()

    def _read_state(self) -> np.ndarray:
        """Every body's (angle, vx, vy, omega), in pymunk's body order."""
        return self.rows.read(_READ, 4)

    def substep(self, h: float, h_next: float) -> None:
        """Advance every drive by one substep of ``h`` [s] and set the control velocities for
        the next substep, of ``h_next`` [s] (the batched path: many robots, read and written
        through ``pymunk.batch``)."""
        self._aim_all(self._gather(lambda group: group.advance(h)), h, h_next)

    def _aim_all(self, twists: tuple[np.ndarray, np.ndarray, np.ndarray], h: float,
                 h_next: float) -> None:
        """The batched :meth:`_aim`: every control body's velocity for the next substep."""
        self._aim_rows(self._everyone, twists, h, h_next)

    def _aim_rows(self, members: np.ndarray, twists: tuple[Any, Any, Any], h: float,
                  h_next: float | np.ndarray, spaces: slice = slice(None)) -> None:
        """:meth:`_aim` of robots ``members`` (twists in their order), read and written as rows;
        ``h_next``: one for all, or each member's; ``spaces``: the Spaces they are in (the
        contact Space's alone: only its rows are read)."""
        ux, uy, omega = (np.asarray(t, dtype=np.float64) for t in twists)  # lists: a plugin's
        self._h[0] = h
        if isinstance(h_next, np.ndarray):
            after = h_next
        else:
            self._h_next[0] = h_next
            after = self._h_next
        state = self.rows.read(_READ, 4, first_only=spaces == slice(0, 1))
        aim_rows(state, self.rows.robot, self.rows.control, members, ux, uy, omega, self._h,
                 after, self.cog, self.rows.out)
        self.rows.write(_WRITE, spaces=spaces)

    def positions(self) -> np.ndarray:
        """Every robot body's position now, (n, 2) [m] (a few robots' read one by one into a
        buffer that the next call overwrites)."""
        if self.batched:
            return self.position_array()
        xy = self._xy
        for k, handle in enumerate(self._handles):
            position = get_position(handle)
            xy[k, 0] = position.x  # two float writes: a third of a Vec2d row assignment's time
            xy[k, 1] = position.y
        return xy

    def motion_array(self) -> np.ndarray:
        """Every robot body's (angle [rad], vx, vy [m/s], omega [rad/s]) now, (n, 4), read in
        one call."""
        return self._read_state()[self.rows.robot]

    def pose_array(self) -> np.ndarray:
        """Every robot body's (x, y [m], angle [rad]) now, (n, 3), read in one call."""
        return self.rows.read(_POSE, 3)[self.rows.robot]

    def position_array(self) -> np.ndarray:
        """Every robot body's position now, (n, 2) [m], read in one call."""
        return self.rows.read(batch.BodyFields.POSITION, 2)[self.rows.robot]

    def _aim(self, k: int, twist: tuple[float, float, float], h: float, h_next: float) -> None:
        """Robot k's control body velocity for the next substep, of ``h_next`` [s], after this
        one of ``h`` (see the module docstring)."""
        ux, uy, omega = twist
        control = self.controls[k]
        if self._anchored[k]:  # from holding: the anchor back to the centre
            self.pivots[k].anchor_a = (0.0, 0.0)
            self._anchored[k] = False
        self._held[k] = None
        cx, cy = self._cog[k]
        handle = self._handles[k]
        vx, vy = aim(get_angle(handle), get_spin(handle), ux, uy, omega, h, h_next, cx, cy)
        last = self._given[k]
        if vx != last[0] or vy != last[1]:
            _SET_VELOCITY(control, (vx, vy))
        if omega != last[2]:
            _SET_SPIN(control, omega)
        self._given[k] = (vx, vy, omega)

    def _hold(self, k: int, twist: tuple[float, float, float], h: float) -> bool:
        """Set robot k's control body to give ``twist`` for a whole step (see the module
        docstring); False if it must be aimed every substep instead (it was aimed for this
        one). A robot driving straight needs one aim for the step: True."""
        omega = twist[2]
        if omega == 0.0:
            self._aim(k, twist, h, h)  # a constant velocity: one aim lasts the step
            return True
        if self._held[k] != twist:
            ux, uy, _ = twist
            cx, cy = self._cog[k]
            ax, ay = anchor(ux, uy, omega, h, cx, cy)
            if not (abs(ax) <= _MAX_ANCHOR and abs(ay) <= _MAX_ANCHOR):
                self._aim(k, twist, h, h)
                return False
            control = self.controls[k]
            last = self._given[k]
            if last[0] != 0.0 or last[1] != 0.0:
                _SET_VELOCITY(control, (0.0, 0.0))
            if omega != last[2]:
                _SET_SPIN(control, omega)
            self._given[k] = (0.0, 0.0, omega)
            self.pivots[k].anchor_a = (ax, ay)
            self._anchored[k] = True
            self._held[k] = twist
        handle = self._handles[k]
        # At each solve the control body's heading equals the robot's (both turn at omega);
        # in free space they already do, to the last bit, and the write is skipped.
        heading = get_angle(handle) + (get_spin(handle) - omega) * h
        if heading != get_angle(self._control_handles[k]):
            _SET_ANGLE(self.controls[k], heading)
        return True
