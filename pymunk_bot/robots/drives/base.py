"""The drive seam: commands in, an acceleration-limited body twist out, for all robots of a kind.

A :class:`DriveGroup` holds every robot of one drive kind in a world as arrays, so the batched
tick advances them together. Each substep it returns the twist the robot body should have
(forward and lateral speed of the body's origin in the robot frame [m/s], yaw rate [rad/s]); the
simulation turns that into the kinematic control body's velocity (the tank pattern, see
docs/physics.md). Its odometry model lives beside it, because what encoders measure depends on
the drive.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pymunk_bot.robots.command import Command
from pymunk_bot.robots.rows import OWN, Rows


class DriveGroup:
    """All robots of one drive kind. Subclasses set ``name`` and implement the methods below."""

    name = ""
    holonomic = False  # True: accepts a lateral speed vy
    # The per-robot state, each a field with a row per robot that the constructor takes from
    # its ``rows`` (``rows.hold(name, initial)``) and the methods change only in place: copies
    # of a scenario sharing a space then hold theirs in shared arrays from birth, and one group
    # over them all bookkeeps them at once (see pymunk_bot.robots.rows). Empty: a group of its
    # own per copy (the constructor then takes only the configs).
    ROWS: tuple[str, ...] = ()
    # Encoder input accumulated since it was last taken (rows per robot, drive-specific
    # columns), changed in place: what its odometry integrates after each tick.
    travel: np.ndarray

    def __init__(self, configs: Sequence[Any], rows: Rows = OWN) -> None:
        self.configs = list(configs)
        self.n = len(self.configs)

    # ------------------------------------------------------------------ stacking
    @classmethod
    def stacked(cls, parts: list[Any], rows: Rows) -> Any:
        """The groups of copies as one group on ``rows``, the whole of the rows the parts hold
        (see :mod:`pymunk_bot.robots.rows`)."""
        return cls([c for part in parts for c in part.configs], rows)

    def settled_rows(self) -> np.ndarray:
        """:meth:`settled` robot by robot (a stacked group's); never, unless a drive can tell."""
        return np.zeros(self.n, dtype=np.bool_)

    def settled_units(self, starts: np.ndarray) -> list[bool]:
        """:meth:`settled` of each run of rows from each of ``starts`` to the next (a stacked
        group's copies)."""
        return np.logical_and.reduceat(self.settled_rows(), starts).tolist()

    # ------------------------------------------------------------------ commands
    def set_command(self, i: int, command: Any) -> None:
        """Robot ``i`` drives with this :class:`Command` (limited to what the drive can do)."""
        raise NotImplementedError

    def command_of(self, i: int) -> Command:
        """The body velocity robot ``i`` is asked for now, after the drive's limits."""
        raise NotImplementedError

    # ------------------------------------------------------------------ physics
    def advance(self, h: float) -> tuple[Any, Any, Any]:
        """Advance the motors by one substep of ``h`` [s]: body twists (ux, uy, omega), each an
        array of shape (n,) (or lists of floats: the tick takes either).

        Also accumulates what the encoders see during the substep (see :meth:`take_travel`).
        """
        raise NotImplementedError

    def settled(self) -> bool:
        """True if every robot's motors have reached their commands, so that further substeps
        return the same twists until a command changes (then :meth:`coast` may stand in for
        :meth:`advance`). A drive that cannot tell says False (the default)."""
        return False

    def coast(self, h: float, substeps: int) -> tuple[Any, Any, Any]:
        """What ``substeps`` calls of :meth:`advance` would do to a settled group (one whose
        motors had settled before the first): the encoders' travel is added, and the twists,
        the same for every substep, are returned as :meth:`advance` returns them."""
        raise NotImplementedError

    def coast_if_settled(self, h: float, substeps: int) -> tuple[Any, Any, Any] | None:
        """:meth:`coast` if the group has :meth:`settled` (one call for both): its twists, or
        None (nothing changed) while some motor is still reaching its command."""
        return self.coast(h, substeps) if self.settled() else None

    def take_travel(self) -> Any:
        """Encoder input accumulated since the last call (rows per robot, drive-specific columns),
        then reset: ``travel``'s copy, ``travel`` zeroed. A drive whose encoders see something
        else overrides it."""
        taken = self.travel.copy()
        self.travel.fill(0.0)  # in place: see ROWS
        return taken

    # ------------------------------------------------------------------ set-up
    def joint_limits(self, i: int, mass: float, moment: float) -> tuple[float, float]:
        """(max force [N], max torque [N m]) of the joints that pull robot ``i``."""
        raise NotImplementedError

    def make_odometry(self, rngs: Sequence[np.random.Generator]) -> Any:
        """This drive's odometry for every robot of the group: an object with ``update(travel)``
        (the array :meth:`take_travel` returns) and ``handle(i)`` (``robot.odometry``: ``pose``,
        ``covariance``). A drive whose odometry is registered under its name in
        ``plugins.odometry`` (the built-ins) is given that one instead; this is the other way a
        plugin drive may bring its own."""
        raise NotImplementedError

    def handle(self, i: int) -> Any:
        """The per-robot view users see as ``robot.drive``."""
        raise NotImplementedError

    def max_speed(self, i: int) -> float:
        """Fastest any point of robot ``i``'s body origin can move [m/s] (for substep choice)."""
        raise NotImplementedError

    def fastest(self, spin: np.ndarray, seconds: float) -> float:
        """The fastest any footprint point of these robots can be driven within ``seconds``
        [m/s]: its motors' speeds now and what they can add by then (a tick with substeps
        takes as many as this speed needs). ``spin`` [m], per robot: how far from its origin
        the points lie that its turn moves (:func:`pymunk_bot.physics.substeps.spin_reach`). A
        drive that does not say: its top speed."""
        return max((c.top_speed() for c in self.configs), default=0.0)


def limit_step(current: np.ndarray, target: np.ndarray, step: np.ndarray | float) -> np.ndarray:
    """Move ``current`` toward ``target`` by at most ``step`` (in place), elementwise."""
    delta = target - current
    np.clip(delta, -step, step, out=delta)
    current += delta
    return current

