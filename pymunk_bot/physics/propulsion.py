"""Every substep: each drive's body twist -> its robot's kinematic control body velocity.

The tank pattern (docs/physics.md): the control body's velocity is what the joints pull the robot
toward. pymunk integrates positions before it solves velocities, so the velocity set now moves
the robot during the next substep: we aim it along the chord of that substep's arc, at the
heading the robot will have half a substep after this one, scaled by sinc(omega h / 2), which
keeps a robot in free space exactly on its commanded arc.

A drive group whose motors have settled on their commands is *held* for the whole step
instead: a turning robot's control body spins at omega about its own centre and the pivot
joint's anchor on it sits where that spin gives the same chord velocity (the anchor is fixed in
the control body's frame, because the wanted velocity turns with the robot), so the substeps run
without Python in between. The control body's heading is matched to the robot's at the start
of each step, as the per-substep aim does every substep; only a robot knocked off its heading
by a contact within a step follows the held heading for the rest of that step.

One path at every size: each drive group advances (or coasts) as rows, and one compiled call
aims or holds its robots, reading and writing their bodies through Chipmunk's own functions
(:mod:`pymunk_bot.physics.steering`, :mod:`pymunk_bot.physics.chipmunk`).
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
import pymunk

from pymunk_bot.physics.chipmunk import CALLS, addresses, read_motions, read_poses
from pymunk_bot.robots.stacking import DriveUnits
from pymunk_bot.physics.row_table import RowTable
from pymunk_bot.physics.steering import (ANCHORED, COG_X, COG_Y, HELD, HELD_STEP,
                                         STEER_COLUMNS, advance_and_aim_wheels, aim_each,
                                         hold_coasting_wheels, hold_each)
from pymunk_bot.robots.drives.diff import DiffDriveGroup
from pymunk_bot.physics.substeps import spin_reach

Twists = tuple[np.ndarray, np.ndarray, np.ndarray]  # ux, uy [m/s], omega [rad/s] as rows


def _rows(twists: tuple[Any, Any, Any]) -> Twists:
    """A drive's twists as float rows (a plugin drive may give lists)."""
    ux, uy, omega = twists
    if type(ux) is np.ndarray and type(uy) is np.ndarray and type(omega) is np.ndarray:
        return ux, uy, omega
    return (np.asarray(ux, dtype=np.float64), np.asarray(uy, dtype=np.float64),
            np.asarray(omega, dtype=np.float64))


class Propulsion:
    """Steers every robot's control body; ``groups`` pairs each drive group with the indices
    (into ``bodies``) of its robots, in the group's order.

    Copies of a scenario sharing a space (:mod:`pymunk_bot.engine.replicas`) pass ``copies``:
    ``groups`` then holds each copy's groups, and each copy is held or aimed as its own
    simulation would be. ``stacked``: the same robots in fewer, larger groups (see
    :mod:`pymunk_bot.robots.stacking`), each copy's group some rows of one of them; the copies'
    groups are then advanced through these, one call for all copies."""

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body],
                 controls: Sequence[pymunk.Body], groups: Sequence[tuple[Any, Sequence[int]]],
                 stacked: Sequence[tuple[Any, Sequence[int], Sequence[int]]] | None = None,
                 copies: bool = False) -> None:
        self.space = space
        self.apart_space: pymunk.Space | None = None  # where robots step apart, once they may
        self.bodies, self.controls = list(bodies), list(controls)
        self.copies = copies
        # What is advanced: each group, or each stacked group with the first row of each
        # copy's part (``stacked`` gives (group, robot indices, part starts)).
        self._drives = ([DriveUnits(g, list(idx), np.asarray(starts, dtype=np.intp))
                         for g, idx, starts in stacked] if stacked
                        else [DriveUnits(g, [int(i) for i in idx], None) for g, idx in groups])
        self.n = len(self.bodies)
        self.pivots = [next(c for c in control.constraints if isinstance(c, pymunk.PivotJoint))
                       for control in self.controls]
        # Each robot's body, control body and pivot as Chipmunk addresses (the pymunk objects
        # above keep them alive), and its steering row (physics/steering.py).
        self.chip = np.stack([addresses(self.bodies), addresses(self.controls),
                              addresses(self.pivots)], axis=1) if self.n else \
            np.zeros((0, 3), dtype=np.intp)
        # every robot body's Chipmunk address, in robot order (read by compiled passes)
        self.body_addresses = np.ascontiguousarray(self.chip[:, 0])
        # Body origin -> centre of gravity [m] (a car's pose point is its rear axle): pymunk
        # moves the centre straight within a substep, so the origin's path needs a correction.
        self.cog = np.array([tuple(b.center_of_gravity) for b in self.bodies]).reshape(-1, 2)
        self.steer = np.zeros((self.n, STEER_COLUMNS))
        self.steer[:, HELD:HELD_STEP + 1] = math.nan
        self.steer[:, COG_X], self.steer[:, COG_Y] = self.cog[:, 0], self.cog[:, 1]
        self._aimed = np.empty(self.n, dtype=np.intp)  # hold_each's robots left to aim
        self._h_hold = np.empty(1)  # [s] one step for every robot held
        self._h_next = np.empty(1)  # [s] one next step for every robot aimed
        # Whole differential drives: their settled motors coast and are held, or their motors
        # advance and their robots are aimed, in one compiled pass each
        # (steering.hold_coasting_wheels, advance_and_aim_wheels); other groups in two calls,
        # the same arithmetic.
        self._wheels = [self._wheel_table(d) if isinstance(d.group, DiffDriveGroup)
                        and d.starts is None else None for d in self._drives]
        self._xy = np.zeros((self.n, 2))  # [m] positions (positions())
        spin = np.array([spin_reach(b) for b in self.bodies])  # [m / rad]
        # Each group's rows (copies' groups: each stacked group's, one call for all copies).
        self._spins = [(drives.group, spin[drives.member_rows]) for drives in self._drives]

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
        second Space) in this tick and in the next, two boolean rows."""
        space = self.space
        h_last = h if h_next is None else h_next
        if apart is not None:
            self._step_split(h, substeps, h_last, *apart)
            return
        # Groups (copies' parts) settled before the step keep their twists through it: held,
        # and coasted (not in a tick before another substep length: every substep is aimed).
        steady: list[tuple[np.ndarray, Twists]] = []  # held, yet aimed each substep
        # Groups still moving, their units (a whole differential drive: its table as well).
        loose: list[tuple[DriveUnits, list[int], RowTable | None]] = []
        for drives, wheels in zip(self._drives, self._wheels):
            if h_last != h:
                moving = drives.every_unit
            elif wheels is not None:  # a whole differential drive: one compiled pass
                count = hold_coasting_wheels(wheels.table, h, substeps)
                moving = [] if count >= 0 else drives.every_unit
                if count > 0:
                    self._aim_later(drives.member_rows, drives.group.twists, count, steady)
            else:
                moving = self._settle(drives, drives.every_unit, h, substeps, steady)
            if moving:
                loose.append((drives, moving, wheels))
        if not (steady or loose):  # every robot held: nothing to do between substeps
            for _ in range(substeps):
                space.step(h)
            return
        after = self._h_next
        for sub in range(substeps):
            after[0] = h_last if sub == substeps - 1 else h  # the substep this aim moves
            if sub:
                for members, (ux, uy, omega) in steady:
                    aim_each(CALLS, self.chip, self.steer, members, ux, uy, omega, h, after)
            for drives, units, wheels in loose:
                if wheels is not None:  # a whole differential drive: one compiled pass
                    advance_and_aim_wheels(wheels.table, h)
                    continue
                rows, _, members = drives.rows(units)
                ux, uy, omega = _rows(drives.advance(h, rows))
                aim_each(CALLS, self.chip, self.steer, members, ux, uy, omega, h, after)
            space.step(h)
            left = substeps - 1 - sub
            if loose and left > 1 and h_last == h:  # motors settled now: held for the rest
                still: list[tuple[DriveUnits, list[int], RowTable | None]] = []
                for drives, units, wheels in loose:
                    moving = self._settle(drives, units, h, left, steady)
                    if moving:
                        still.append((drives, moving, wheels))
                loose = still

    def _wheel_table(self, drives: DriveUnits) -> RowTable:
        """What hold_coasting_wheels reads of a whole differential drive, in its slots' order."""
        group, f64, intp = drives.group, np.float64, np.intp
        return RowTable([(CALLS, None, intp, 1), (self, "chip", intp, 2),
                         (self, "steer", f64, 2), (drives, "member_rows", intp, 1),
                         (group, "commanded", f64, 2), (group, "target", f64, 2),
                         (group, "turning", f64, 2), (group, "travel", f64, 2),
                         (group, "track", f64, 1), (group, "twist_rows", f64, 2),
                         (self._aimed, None, intp, 1), (self._h_hold, None, f64, 1),
                         (group, "max_accel", f64, 1), (self._h_next, None, f64, 1)])

    def _settle(self, drives: DriveUnits, units: list[int], h: float, substeps: int,
                steady: list[tuple[np.ndarray, Twists]]) -> list[int]:
        """Of these units of ``drives``, those whose motors have settled coast through
        ``substeps`` substeps of ``h`` [s] and are held for them; returns the units still
        moving."""
        members, twists, moving = drives.coast_settled(units, h, substeps)
        if twists is not None:
            self._hold(members, _rows(twists), h, steady)
        return moving

    def _hold(self, members: np.ndarray, twists: Twists, h: float,
              steady: list[tuple[np.ndarray, Twists]]) -> None:
        """Hold robots ``members`` (their twists in that order) for a step of substeps ``h``
        [s]; those that cannot be held (see ``hold_each``) go on ``steady``, aimed for this
        substep and to be aimed every other."""
        ux, uy, omega = twists
        self._h_hold[0] = h
        count = hold_each(CALLS, self.chip, self.steer, members, ux, uy, omega, self._h_hold,
                          self._aimed)
        self._aim_later(members, twists, count, steady)

    def _aim_later(self, members: np.ndarray, twists: Twists, count: int,
                   steady: list[tuple[np.ndarray, Twists]]) -> None:
        """The first ``count`` of ``_aimed`` (positions in ``members``, whose twists are
        ``twists``) could not be held: on ``steady``, aimed every substep."""
        if count:
            ux, uy, omega = twists
            j = self._aimed[:count].copy()
            steady.append((members[j], (ux[j], uy[j], omega[j])))

    def _step_split(self, h: float, substeps: int, h_last: float, apart: np.ndarray,
                    apart_next: np.ndarray) -> None:
        """``step`` with the robots ``apart`` (a boolean row) stepping apart: those nearer
        step in the contact Space, substep by substep, then those apart take one step of the
        whole tick in theirs. Each robot's last aim is for the step it takes first in the next
        tick: the tick when it steps apart then (``apart_next``), else ``h_last``. As in any
        tick, a drive whose motors have settled coasts through it and its robots are held for
        their step (a substep, or the tick apart), when the next one is as long; the others
        are aimed before each of their steps, their drives advancing substep by substep."""
        assert self.apart_space is not None
        dt = h * substeps
        own = np.where(apart, dt, h)  # [s] each robot's step in this tick
        first_next = np.where(apart_next, dt, h_last)  # [s] each robot's next step
        ux, uy, omega = np.zeros(self.n), np.zeros(self.n), np.zeros(self.n)
        aimed = np.ones(self.n, dtype=bool)  # aimed before each of its steps, not held
        moving: list[tuple[Any, np.ndarray]] = []  # the drives advancing substep by substep
        for drives in self._drives:
            members, twists, units = drives.coast_settled(drives.every_unit, h, substeps)
            if units:
                moving.append((drives.group, members))
                continue
            assert twists is not None
            ux[members], uy[members], omega[members] = _rows(twists)
            held = members[own[members] == first_next[members]]
            aimed[held] = False
            count = hold_each(CALLS, self.chip, self.steer, held, ux[held], uy[held],
                              omega[held], own[held], self._aimed)
            aimed[held[self._aimed[:count]]] = True  # their anchors too far: aimed instead
        near = np.flatnonzero(~apart & aimed)
        away = np.flatnonzero(apart & aimed)
        for sub in range(substeps):
            for group, members in moving:
                ux[members], uy[members], omega[members] = _rows(group.advance(h))
            if near.size:
                self._h_next[0] = h
                aim_each(CALLS, self.chip, self.steer, near, ux[near], uy[near], omega[near],
                         h, first_next[near] if sub == substeps - 1 else self._h_next)
            self.space.step(h)
        if away.size:  # their motors advanced the whole tick, in substeps, as the others'
            aim_each(CALLS, self.chip, self.steer, away, ux[away], uy[away], omega[away], dt,
                     first_next[away])
        if apart.any():
            self.apart_space.step(dt)

    def adopt(self, previous: "Propulsion") -> None:
        """Take over what ``previous`` knew of the bodies both steer (the twists held, the
        anchors off centre), as a fleet of copies rebuilds its Propulsion after one copy's
        reset."""
        known = {id(body): j for j, body in enumerate(previous.bodies)}
        for k, body in enumerate(self.bodies):
            j = known.get(id(body))
            if j is not None:
                self.steer[k, HELD:ANCHORED + 1] = previous.steer[j, HELD:ANCHORED + 1]

    def step_apart_in(self, apart: pymunk.Space) -> None:
        """Robots may step apart, in ``apart`` (physics/apart.py)."""
        self.apart_space = apart

    def positions(self) -> np.ndarray:
        """Every robot body's position now, (n, 2) [m], into a buffer that the next call
        overwrites."""
        read_poses(CALLS, self.body_addresses, self._xy)
        return self._xy

    def motion_array(self) -> np.ndarray:
        """Every robot body's (angle [rad], vx, vy [m/s], omega [rad/s]) now, (n, 4)."""
        out = np.empty((self.n, 4))
        read_motions(CALLS, self.body_addresses, out)
        return out

    def pose_array(self) -> np.ndarray:
        """Every robot body's (x, y [m], angle [rad]) now, (n, 3)."""
        out = np.empty((self.n, 3))
        read_poses(CALLS, self.body_addresses, out)
        return out

    def position_array(self) -> np.ndarray:
        """Every robot body's position now, (n, 2) [m] (an array of its own)."""
        return self.positions().copy()
