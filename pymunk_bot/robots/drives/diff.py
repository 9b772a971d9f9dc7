"""Differential drive: two wheels ``track_width`` apart, each limited in speed and acceleration.

pymunk integrates positions before it solves velocities, so a velocity given to the control body
in one substep moves the robot in the next. The wheel speeds the encoders see in a substep are
therefore the ones commanded one substep earlier: the motor lags its command by one substep.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numba
import numpy as np

from pymunk_bot.robots.command import Command
from pymunk_bot.robots.drives.base import DriveGroup
from pymunk_bot.robots.rows import OWN, Rows


# [m/s^2] the most sideways acceleration a wheel's grip on a floor gives (about 1 g)
WHEEL_GRIP = 9.81


def wheel_speeds(v: float, omega: float, track_width: float) -> tuple[float, float]:
    """(v [m/s], omega [rad/s]) -> (left, right) wheel speeds [m/s]."""
    return _wheel_speeds(float(v), float(omega), float(track_width))


class DiffDriveGroup(DriveGroup):
    """Every differential-drive robot of a world; commands are wheel speeds or a :class:`Command`."""

    name = "diff"
    ROWS = ("target", "commanded", "turning", "travel")  # the per-robot state

    def __init__(self, configs: Sequence[Any], rows: Rows = OWN) -> None:
        super().__init__(configs)
        self.track = np.array([c.track_width for c in configs], dtype=float)  # [m]
        self.max_wheel = np.array([c.max_wheel_speed for c in configs], dtype=float)  # [m/s]
        self.max_accel = np.array([c.max_accel for c in configs], dtype=float)  # [m/s^2] per wheel
        # Per robot (left, right), a row each.
        wheels = np.zeros((self.n, 2))
        # commanded wheel speeds after the speed limit [m/s]
        self.target = rows.hold("target", wheels)
        # acceleration-limited speeds to the motors [m/s]
        self.commanded = rows.hold("commanded", wheels.copy())
        # speeds the wheels turn at in this substep [m/s]
        self.turning = rows.hold("turning", wheels.copy())
        self.travel = rows.hold("travel", wheels.copy())  # wheel travel since last taken [m]
        # The same as floats: cheaper than numpy's scalars robot by robot.
        self._track = self.track.tolist()
        self._every = np.arange(self.n, dtype=np.intp)
        # (ux, uy, omega) of every robot, rows written by advance and coast [m/s, m/s, rad/s]
        self.twist_rows = np.zeros((3, self.n))
        self.twists = (self.twist_rows[0], self.twist_rows[1], self.twist_rows[2])

    def set_wheel_speeds(self, i: int, left: float, right: float) -> None:
        """Robot ``i``'s wheel speeds [m/s]; both are scaled by one factor to respect the speed
        limit, so the turn radius is kept."""
        left, right = float(left), float(right)
        if not _set_wheels(i, left, right, self.max_wheel, self.target):
            raise ValueError(f"wheel speeds must be finite (got {left}, {right})")

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
        if not _command_rows(rows, np.asarray(v, dtype=np.float64),
                             np.asarray(omega, dtype=np.float64), self.track, self.max_wheel,
                             self.target):
            raise ValueError("commands must be finite")

    def command_of(self, i: int) -> Command:
        left, right = self.target[i]
        return Command(float(0.5 * (left + right)), float((right - left) / self.track[i]))

    def advance(self, h: float, rows: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """See :meth:`DriveGroup.advance`; ``rows``: only these robots (a stacked group's
        copies, see :mod:`pymunk_bot.robots.stacking`)."""
        ux, uy, omega = self._twists_for(rows)
        _advance_rows(self._every if rows is None else rows, self.commanded, self.target,
                      self.turning, self.travel, self.max_accel, self.track, h, ux, omega)
        return ux, uy, omega

    def settled(self) -> bool:
        return _equal_rows(self.commanded, self.target)

    def settled_rows(self) -> np.ndarray:
        """:meth:`settled` robot by robot (a stacked group's)."""
        return (self.commanded == self.target).all(axis=1)

    def settled_units(self, starts: np.ndarray) -> list[bool]:
        flags = np.empty(starts.shape[0], dtype=np.bool_)
        _settled_units(self.commanded, self.target, starts, flags)
        return flags.tolist()

    def coast(self, h: float, substeps: int, rows: np.ndarray | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """See :meth:`DriveGroup.coast`; ``rows``: as in :meth:`advance`."""
        ux, uy, omega = self._twists_for(rows)
        # [s] the wheels turn at their commanded speeds throughout
        _coast_rows(self._every if rows is None else rows, self.commanded, self.turning,
                    self.travel, self.track, h * substeps, ux, omega)
        return ux, uy, omega

    def coast_if_settled(self, h: float, substeps: int
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """See :meth:`DriveGroup.coast_if_settled`: one compiled call."""
        ux, uy, omega = self.twists
        if coast_settled_rows(self.commanded, self.target, self.turning, self.travel,
                              self.track, h * substeps, ux, omega):
            return self.twists
        return None

    def _twists_for(self, rows: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Arrays for the twists of these rows; every robot's (None) are the same arrays each
        call, valid until the next ``advance`` or ``coast`` (the tick uses them at once)."""
        if rows is None:
            return self.twists
        return np.empty(rows.shape[0]), np.zeros(rows.shape[0]), np.empty(rows.shape[0])


    def joint_limits(self, i: int, mass: float, moment: float) -> tuple[float, float]:
        # Force for the fastest allowed change of speed plus turns (the centripetal
        # v*omega <= v_max^2 / L), but never more sideways grip than a wheel's traction on a
        # floor, about 1 g: a faster, tighter turn skids, as on a real floor. A larger cap lets
        # the joints out-push contacts (see docs/physics.md). The torque follows the fastest
        # spin-up, wheels accelerating in opposite directions: alpha = 2 a / L, with margin.
        a, track = self.max_accel[i], self.track[i]
        force = mass * (a + min(self.max_wheel[i] ** 2 / track, WHEEL_GRIP))
        torque = max(force * track / 2.0, 2.0 * moment * 2.0 * a / track)
        return force, torque

    def max_speed(self, i: int) -> float:
        return float(self.max_wheel[i])

    def fastest(self, spin: np.ndarray, seconds: float) -> float:
        return _fastest(self.commanded, self.turning, self.track, self.max_accel, spin, seconds)

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


# The motors' arithmetic, robot by robot over rows: one compiled implementation for one robot,
# a fleet, or the rows of a stacked group's copies (so each gets the same floats on any).
@numba.njit(cache=True)
def _command_rows(rows: np.ndarray, v: np.ndarray, omega: np.ndarray, track: np.ndarray,
                  max_wheel: np.ndarray, target: np.ndarray) -> bool:
    """set_command of ``Command(v[j], omega[j])`` for robot ``rows[j]``, into ``target``;
    False, and nothing written, if a command is not finite."""
    for j in range(rows.shape[0]):
        if not (math.isfinite(v[j]) and math.isfinite(omega[j])):
            return False
    for j in range(rows.shape[0]):
        i = rows[j]
        left, right = _wheel_speeds(v[j], omega[j], track[i])
        _set_wheels(i, left, right, max_wheel, target)
    return True


@numba.njit(cache=True)
def _wheel_speeds(v: float, omega: float, track: float) -> tuple[float, float]:
    """wheel_speeds' formula (left, right) [m/s], once for the Python and the compiled paths."""
    half = 0.5 * omega * track
    return v - half, v + half


@numba.njit(cache=True)
def _set_wheels(i: int, left: float, right: float, max_wheel: np.ndarray,
                target: np.ndarray) -> bool:
    """Robot i's target wheel speeds [m/s], both scaled by one factor to respect its speed
    limit (the turn radius is kept); False, and nothing written, if one is not finite."""
    if not (math.isfinite(left) and math.isfinite(right)):
        return False
    peak = max(abs(left), abs(right))
    if peak > max_wheel[i]:
        scale = max_wheel[i] / peak
        left, right = left * scale, right * scale
    target[i, 0], target[i, 1] = left, right
    return True


@numba.njit(cache=True)
def _advance_rows(rows: np.ndarray, commanded: np.ndarray, target: np.ndarray,
                  turning: np.ndarray, travel: np.ndarray, max_accel: np.ndarray,
                  track: np.ndarray, h: float, ux: np.ndarray, omega: np.ndarray) -> None:
    """One substep of ``h`` [s]: the wheels turn at the speeds commanded one substep earlier
    (the encoders count that), the commands move toward their targets by at most
    max_accel * h, and the body twists (ux [m/s], omega [rad/s]) of the new commands."""
    for j in range(rows.shape[0]):
        _advance_one(rows[j], j, commanded, target, turning, travel, max_accel, track, h, ux,
                     omega)


@numba.njit(cache=True)
def advance_every_row(commanded: np.ndarray, target: np.ndarray, turning: np.ndarray,
                      travel: np.ndarray, max_accel: np.ndarray, track: np.ndarray, h: float,
                      ux: np.ndarray, omega: np.ndarray) -> None:
    """:func:`_advance_rows` of every robot of the group, in order."""
    for i in range(commanded.shape[0]):
        _advance_one(i, i, commanded, target, turning, travel, max_accel, track, h, ux, omega)


@numba.njit(cache=True)
def _advance_one(i: int, j: int, commanded: np.ndarray, target: np.ndarray,
                 turning: np.ndarray, travel: np.ndarray, max_accel: np.ndarray,
                 track: np.ndarray, h: float, ux: np.ndarray, omega: np.ndarray) -> None:
    """Robot ``i``'s substep of :func:`_advance_rows`, its twist written at ``j``."""
    _turn_wheels(i, commanded, turning, travel, h)
    step = max_accel[i] * h
    for wheel in range(2):
        speed = commanded[i, wheel]
        commanded[i, wheel] = speed + min(step, max(-step, target[i, wheel] - speed))
    _twist(i, j, commanded, track, ux, omega)


@numba.njit(cache=True)
def _coast_rows(rows: np.ndarray, commanded: np.ndarray, turning: np.ndarray,
                travel: np.ndarray, track: np.ndarray, span: float, ux: np.ndarray,
                omega: np.ndarray) -> None:
    """Settled motors over ``span`` [s]: the wheels turn at their commanded speeds throughout;
    the body twists as in :func:`_advance_rows`."""
    for j in range(rows.shape[0]):
        i = rows[j]
        _turn_wheels(i, commanded, turning, travel, span)
        _twist(i, j, commanded, track, ux, omega)


@numba.njit(cache=True)
def coast_settled_rows(commanded: np.ndarray, target: np.ndarray, turning: np.ndarray,
                       travel: np.ndarray, track: np.ndarray, span: float, ux: np.ndarray,
                       omega: np.ndarray) -> bool:
    """:func:`_coast_rows` of every robot over ``span`` [s] if every motor has reached its
    target (True), else nothing (False). Public: the propulsion holds the robots in the same
    compiled pass (physics/steering.py)."""
    if not _equal_rows(commanded, target):
        return False
    for i in range(commanded.shape[0]):
        _turn_wheels(i, commanded, turning, travel, span)
        _twist(i, i, commanded, track, ux, omega)
    return True


@numba.njit(cache=True)
def _turn_wheels(i: int, commanded: np.ndarray, turning: np.ndarray, travel: np.ndarray,
                 span: float) -> None:
    """Robot ``i``'s wheels turn at their commanded speeds [m/s] for ``span`` [s]."""
    for wheel in range(2):
        turning[i, wheel] = commanded[i, wheel]
        travel[i, wheel] += commanded[i, wheel] * span


@numba.njit(cache=True)
def _twist(i: int, j: int, commanded: np.ndarray, track: np.ndarray, ux: np.ndarray,
           omega: np.ndarray) -> None:
    """Row ``j`` of the twists: robot ``i``'s body speed [m/s] and yaw rate [rad/s] from its
    commanded wheel speeds."""
    left, right = commanded[i, 0], commanded[i, 1]
    ux[j] = 0.5 * (left + right)
    omega[j] = (right - left) / track[i]


@numba.njit(cache=True)
def _equal_rows(a: np.ndarray, b: np.ndarray) -> bool:
    """Every element of ``a`` equals ``b``'s (what np.array_equal says, for a tenth of its cost
    on a few robots)."""
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            if a[i, j] != b[i, j]:
                return False
    return True


@numba.njit(cache=True)
def _settled_units(commanded: np.ndarray, target: np.ndarray, starts: np.ndarray,
                   flags: np.ndarray) -> None:
    """Per run of rows from each of ``starts`` to the next: every wheel's command has reached
    its target."""
    for u in range(starts.shape[0]):
        stop = starts[u + 1] if u + 1 < starts.shape[0] else commanded.shape[0]
        flags[u] = _equal_rows(commanded[starts[u]:stop], target[starts[u]:stop])


@numba.njit(cache=True)
def _fastest(commanded: np.ndarray, turning: np.ndarray, track: np.ndarray,
             max_accel: np.ndarray, spin: np.ndarray, seconds: float) -> float:
    """The fastest footprint point [m/s] within ``seconds``: |v| + |omega| * spin of the
    motors' (``commanded``) and the wheels' (``turning``) speeds, plus what the wheels gain
    (each at most ``max_accel``: the centre too, the turn twice that over the track)."""
    fastest = 0.0
    for i in range(track.shape[0]):
        lever = spin[i] / track[i]
        gain = max_accel[i] * (1.0 + 2.0 * lever) * seconds
        for wheels in (commanded, turning):
            left, right = wheels[i, 0], wheels[i, 1]
            fastest = max(fastest, 0.5 * abs(left + right) + abs(right - left) * lever + gain)
    return fastest
