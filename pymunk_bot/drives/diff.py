"""Differential drive: two wheels ``track_width`` apart, each limited in speed and acceleration.

pymunk integrates positions before it solves velocities, so a velocity given to the control body
in one substep moves the robot in the next. The wheel speeds the encoders see in a substep are
therefore the ones commanded one substep earlier: the motor lags its command by one substep.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from .. import physics
from ..command import Command
from .base import SMALL_GROUP, DriveGroup, limit_step


def wheel_speeds(v: float, omega: float, track_width: float) -> tuple[float, float]:
    """(v [m/s], omega [rad/s]) -> (left, right) wheel speeds [m/s]."""
    half = 0.5 * omega * track_width
    return v - half, v + half


class DiffDriveGroup(DriveGroup):
    """Every differential-drive robot of a world; commands are wheel speeds or a :class:`Command`."""

    name = "diff"
    ROWS = ("target", "commanded", "turning", "_travel")  # the per-robot state

    def __init__(self, configs: Sequence[Any]) -> None:
        super().__init__(configs)
        self.track = np.array([c.track_width for c in configs], dtype=float)  # [m]
        self.max_wheel = np.array([c.max_wheel_speed for c in configs], dtype=float)  # [m/s]
        self.max_accel = np.array([c.max_accel for c in configs], dtype=float)  # [m/s^2] per wheel
        # Per robot (left, right): rows of an array, or for a small group lists of floats
        # (cheaper to touch one by one); both index the same way.
        self.small = self.n < SMALL_GROUP
        zeros = (lambda: [[0.0, 0.0] for _ in range(self.n)]) if self.small else (
            lambda: np.zeros((self.n, 2)))
        self.target: Any = zeros()  # commanded wheel speeds after the speed limit [m/s]
        self.commanded: Any = zeros()  # acceleration-limited speeds sent to the motors [m/s]
        self.turning: Any = zeros()  # speeds the wheels turn at in this substep [m/s]
        self._travel: Any = zeros()  # wheel travel since take_travel [m]
        # The same as floats: cheaper than numpy's scalars robot by robot.
        self._accel = self.max_accel.tolist()
        self._track = self.track.tolist()
        self._max_wheel = self.max_wheel.tolist()
        self._twists: tuple[list[float], list[float], list[float]] | None = None  # of commanded

    @classmethod
    def stacked(cls, parts: list[Any]) -> "DiffDriveGroup":
        """See :meth:`DriveGroup.stacked`: every part then works on arrays."""
        whole = super().stacked(parts)
        for part in parts + [whole]:
            part.small, part._twists = False, None
        return whole

    def set_wheel_speeds(self, i: int, left: float, right: float) -> None:
        """Robot ``i``'s wheel speeds [m/s]; both are scaled by one factor to respect the speed
        limit, so the turn radius is kept."""
        left, right = float(left), float(right)
        if not (math.isfinite(left) and math.isfinite(right)):
            raise ValueError(f"wheel speeds must be finite (got {left}, {right})")
        peak = max(abs(left), abs(right))
        limit = self._max_wheel[i]
        if peak > limit:
            scale = limit / peak
            left, right = left * scale, right * scale
        self.target[i] = [left, right]

    def set_command(self, i: int, command: Any) -> None:
        """A :class:`Command`, or a (left, right) pair of wheel speeds [m/s] (the older form)."""
        if isinstance(command, Command):
            if command.vy != 0.0:
                raise ValueError(f"a diff drive cannot move sideways (vy = {command.vy:g})")
            self.set_wheel_speeds(i, *wheel_speeds(command.v, command.omega, self._track[i]))
        else:
            left, right = command
            self.set_wheel_speeds(i, left, right)

    def set_velocities(self, rows: np.ndarray, v: np.ndarray, omega: np.ndarray) -> None:
        """:meth:`set_command` with ``Command(v, omega)`` for these robots at once (arrays
        [m/s], [rad/s]): the same wheel speeds, to the bit."""
        if not (np.isfinite(v).all() and np.isfinite(omega).all()):
            raise ValueError("commands must be finite")
        half = 0.5 * omega * self.track[rows]  # wheel_speeds, on arrays
        left, right = v - half, v + half
        peak = np.maximum(np.abs(left), np.abs(right))
        limit = self.max_wheel[rows]
        over = peak > limit
        if over.any():  # both scaled by one factor, as set_wheel_speeds does
            scale = limit[over] / peak[over]
            left[over] *= scale
            right[over] *= scale
        self.target[rows] = np.stack((left, right), axis=1)

    def command_of(self, i: int) -> Command:
        left, right = self.target[i]
        return Command(float(0.5 * (left + right)), float((right - left) / self.track[i]))

    def advance(self, h: float, rows: np.ndarray | None = None) -> tuple[Any, Any, Any]:
        """See :meth:`DriveGroup.advance`; ``rows``: only these robots (a stacked group's
        copies, see :mod:`pymunk_bot.stacking`), with the same arithmetic."""
        if self.small:
            return self._advance_each(h)
        at = slice(None) if rows is None else rows  # every robot: views, changed in place
        commanded = self.commanded[at]
        self.turning[at] = commanded
        self._travel[at] += commanded * h
        limit_step(commanded, self.target[at], (self.max_accel[at] * h)[:, None])
        self.commanded[at] = commanded
        return self._twists_of(commanded, rows)

    def _twists_of(self, commanded: np.ndarray, rows: np.ndarray | None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ux, uy, omega) of these commanded wheel speeds (of ``rows``, or of every robot)."""
        left, right = commanded[:, 0], commanded[:, 1]
        track = self.track if rows is None else self.track[rows]
        return 0.5 * (left + right), np.zeros(left.shape[0]), (right - left) / track

    def _advance_each(self, h: float) -> tuple[list[float], list[float], list[float]]:
        """The same arithmetic robot by robot: cheaper than numpy for a few robots."""
        self._twists = None  # the commanded speeds may change
        for i, (l0, r0) in enumerate(self.commanded):
            self.turning[i] = [l0, r0]
            travel = self._travel[i]
            travel[0] += l0 * h
            travel[1] += r0 * h
            step = self._accel[i] * h
            lt, rt = self.target[i]
            self.commanded[i] = [l0 + min(step, max(-step, lt - l0)),
                                 r0 + min(step, max(-step, rt - r0))]
        return self._twists_each()

    def _twists_each(self) -> tuple[list[float], list[float], list[float]]:
        """(ux, uy, omega) of the commanded wheel speeds, robot by robot."""
        ux, omega = [], []
        for (left, right), track in zip(self.commanded, self._track):
            ux.append(0.5 * (left + right))
            omega.append((right - left) / track)
        return ux, [0.0] * self.n, omega

    def settled(self) -> bool:
        if self.small:
            return self.commanded == self.target  # lists of [left, right]: compared in C
        return bool(np.array_equal(self.commanded, self.target))

    def settled_rows(self) -> np.ndarray:
        """:meth:`settled` robot by robot (on arrays: a stacked group)."""
        return (self.commanded == self.target).all(axis=1)

    def coast(self, h: float, substeps: int, rows: np.ndarray | None = None
              ) -> tuple[Any, Any, Any]:
        """See :meth:`DriveGroup.coast`; ``rows``: as in :meth:`advance`."""
        span = h * substeps  # [s] the wheels turn at their commanded speeds throughout
        if self.small:
            for wheels, turning, travel in zip(self.commanded, self.turning, self._travel):
                turning[:] = wheels
                travel[0] += wheels[0] * span
                travel[1] += wheels[1] * span
            if self._twists is None:  # settled: the same until the commanded speeds change
                self._twists = self._twists_each()
            return self._twists
        at = slice(None) if rows is None else rows
        commanded = self.commanded[at]
        self.turning[at] = commanded
        self._travel[at] += commanded * span
        return self._twists_of(commanded, rows)

    def take_travel(self) -> Any:
        travel = self._travel
        if self.small:
            self._travel = [[0.0, 0.0] for _ in range(self.n)]
            return travel
        taken = travel.copy()
        travel.fill(0.0)  # in place: a stacked group's parts keep viewing its rows
        return taken

    def joint_limits(self, i: int, mass: float, moment: float) -> tuple[float, float]:
        # Force for the fastest allowed change of speed plus turns (the centripetal
        # v*omega <= v_max^2 / L), but never more sideways grip than a wheel's traction on a
        # floor, about 1 g: a faster, tighter turn skids, as on a real floor. A larger cap lets
        # the joints out-push contacts (see docs/physics.md). The torque follows the fastest
        # spin-up, wheels accelerating in opposite directions: alpha = 2 a / L, with margin.
        a, track = self.max_accel[i], self.track[i]
        force = mass * (a + min(self.max_wheel[i] ** 2 / track, physics.GRAVITY))
        torque = max(force * track / 2.0, 2.0 * moment * 2.0 * a / track)
        return force, torque

    def max_speed(self, i: int) -> float:
        return float(self.max_wheel[i])

    def handle(self, i: int) -> "DiffDrive":
        return DiffDrive(self, i)


class DiffDrive:
    """One robot's view of its differential drive (``robot.drive``)."""

    def __init__(self, group: DiffDriveGroup, index: int) -> None:
        self._group = group
        self._i = index
        self.track_width = float(group.track[index])  # [m]
        self.max_wheel_speed = float(group.max_wheel[index])  # [m/s]
        self.max_accel = float(group.max_accel[index])  # [m/s^2]

    @property
    def target(self) -> tuple[float, float]:
        """Commanded (left, right) wheel speeds after the speed limit [m/s]."""
        left, right = self._group.target[self._i]
        return (float(left), float(right))

    @property
    def commanded(self) -> tuple[float, float]:
        """Acceleration-limited (left, right) speeds sent to the motors [m/s]."""
        left, right = self._group.commanded[self._i]
        return (float(left), float(right))

    @property
    def wheel_speeds(self) -> tuple[float, float]:
        """(left, right) speeds the wheels turned at in the last substep [m/s]."""
        left, right = self._group.turning[self._i]
        return (float(left), float(right))

    @property
    def command(self) -> Command:
        """The body velocity asked for now."""
        return self._group.command_of(self._i)

    def set_wheel_speeds(self, left: float, right: float) -> None:
        """Command wheel speeds [m/s] (scaled by one factor to the speed limit)."""
        self._group.set_wheel_speeds(self._i, left, right)
