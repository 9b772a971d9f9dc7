"""Copies of one scenario bookkept in one pass: the copies' fleets, drive groups and odometry
stacked into one object each, whose arrays hold every copy's rows (copy 0's robots first).

Each copy keeps its own objects, and its robots' handles still read them, but their per-robot
fields become views of the stacked object's arrays, so a write on either side is seen by both.
A class opts in by naming its per-robot fields (``ROWS``) and giving a ``stacked(parts)``
classmethod, which builds the whole from the parts' configs and joins their rows with
:func:`join_rows`, and ``split(parts)``, which gives each part arrays of its own again (before
a copy is rebuilt). Its methods must then change those fields in place, never rebind them.

Per-tick work on the stack (coast, travel, odometry, distance and goals: engine/bookkeeping.py
for the last three) does the arithmetic a copy's own objects do on their rows, operation for
operation, so the floats are the same.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

# Counts the times per-robot fields were rebound (join_rows, split_rows): compiled passes that
# hold arrays by address take them anew when it changes (physics/row_table.py).
generation = 0


def join_rows(whole: Any, parts: Sequence[Any], fields: Sequence[str]) -> None:
    """Each of ``fields`` of ``whole`` becomes the parts' rows one after another, and each
    part's field a view of its rows."""
    global generation
    generation += 1
    for name in fields:
        values = [np.asarray(getattr(part, name)) for part in parts]
        joined = np.concatenate(values)
        setattr(whole, name, joined)
        start = 0
        for part, value in zip(parts, values):
            setattr(part, name, joined[start:start + value.shape[0]])
            start += value.shape[0]


def split_rows(whole: Any, parts: Sequence[Any], fields: Sequence[str]) -> None:
    """Each part's ``fields`` back to arrays of its own, copied from its rows of ``whole``."""
    global generation
    generation += 1
    for name in fields:
        joined, start = getattr(whole, name), 0
        for part in parts:
            rows = len(getattr(part, name))
            setattr(part, name, joined[start:start + rows].copy())
            start += rows


def join_odometry(whole: Any, parts: Sequence[Any]) -> None:
    """:func:`join_rows` of an odometry group's ``ROWS`` and of its encoders' ``ROWS``."""
    join_rows(whole, parts, whole.ROWS)
    join_rows(whole.encoders, [part.encoders for part in parts], whole.encoders.ROWS)


def split_odometry(whole: Any, parts: Sequence[Any]) -> None:
    """:func:`split_rows` of an odometry group's ``ROWS`` and of its encoders' ``ROWS``."""
    split_rows(whole, parts, whole.ROWS)
    split_rows(whole.encoders, [part.encoders for part in parts], whole.encoders.ROWS)


class Stack:
    """The fleets, drive groups and odometry groups of ``sims`` (copies of one scenario), each
    stacked into one; see :meth:`of`."""

    def __init__(self, sims: Sequence[Any]) -> None:
        self._fleets = [sim.built.fleet for sim in sims]
        self.fleet = type(self._fleets[0]).stacked(self._fleets)
        self.per_copy = len(sims[0].robots)  # robots of each copy
        slots = len(sims[0].built.drive_groups)
        self._drives = [[sim.built.drive_groups[j][0] for sim in sims] for j in range(slots)]
        self._odometry = [[sim.built.odometry_groups[j][0] for sim in sims] for j in range(slots)]
        # Each whole, with its robots' indices and the first row of each copy's part.
        self.drive_groups: list[tuple[Any, list[int], list[int]]] = []
        self.pairs: list[tuple[Any, Any]] = []  # (drive group, its odometry), stacked
        for j, (drives, odometries) in enumerate(zip(self._drives, self._odometry)):
            members = [copy * self.per_copy + i for copy, sim in enumerate(sims)
                       for i in sim.built.drive_groups[j][1]]
            starts = np.cumsum([0] + [part.n for part in drives[:-1]]).tolist()
            whole = type(drives[0]).stacked(drives)
            self.drive_groups.append((whole, members, starts))
            self.pairs.append((whole, type(odometries[0]).stacked(odometries)))
        # Robot (copy * per_copy + index in its copy) -> (its stacked drive group, its row).
        self.row_of = {robot: (whole, row) for whole, members, _ in self.drive_groups
                       for row, robot in enumerate(members)}

    @classmethod
    def of(cls, sims: Sequence[Any]) -> "Stack | None":
        """The stack of these copies, or None if some group cannot be stacked (its class
        names no ``ROWS``) or a copy has no robots."""
        first = sims[0].built
        groups = [first.fleet] + [g for g, _ in first.drive_groups + first.odometry_groups]
        if not first.robots or not all(getattr(type(g), "ROWS", ()) for g in groups):
            return None
        return cls(sims)

    def split(self) -> None:
        """Every copy's objects back on arrays of their own (the stack is not used after)."""
        self.fleet.split(self._fleets)
        for (drive, odometry), drives, odometries in zip(self.pairs, self._drives, self._odometry):
            drive.split(drives)
            odometry.split(odometries)


class DriveUnits:
    """A drive group as ``Propulsion``'s per-robot path advances it: whole (one unit), or
    (``starts``: stacked) as units, the rows of each copy's part from its start on."""

    def __init__(self, group: Any, members: list[int], starts: np.ndarray | None) -> None:
        self.group = group
        self.members = members  # robot index of each row
        self.member_rows = np.asarray(members, dtype=np.intp)  # the same, as an array
        self.starts = starts
        self.units = 1 if starts is None else starts.shape[0]
        self.every_unit = list(range(self.units))
        if starts is not None:
            ends = np.append(starts[1:], len(members))
            self._unit_rows = [np.arange(a, b) for a, b in zip(starts.tolist(), ends.tolist())]

    def coast_settled(self, units: list[int], h: float, substeps: int
                      ) -> tuple[np.ndarray, tuple[Any, Any, Any] | None, list[int]]:
        """Of these units, those whose motors have reached their commands coast over
        ``substeps`` substeps of ``h`` [s]: (their robots, as an array, their twists in that
        order, the units still moving). Random commands leave most units moving every tick."""
        if self.starts is None:  # one unit: the whole group, in one call
            twists = self.group.coast_if_settled(h, substeps)
            return (self.member_rows, twists, []) if twists is not None else \
                (self.member_rows, None, units)
        settled = self.group.settled_units(self.starts)
        calm = [u for u in units if settled[u]]
        if not calm:
            return self.member_rows, None, units
        moving = [u for u in units if not settled[u]] if len(calm) < len(units) else []
        rows, _, member_rows = self.rows(calm)
        return member_rows, self.coast(h, substeps, rows), moving

    def rows(self, units: list[int]) -> tuple[np.ndarray | None, list[int], np.ndarray]:
        """The rows of these units (None: every row) and their robots, as a list and an array."""
        if len(units) == self.units:
            return None, self.members, self.member_rows
        rows = np.concatenate([self._unit_rows[u] for u in units])
        return rows, [self.members[r] for r in rows.tolist()], self.member_rows[rows]

    def advance(self, h: float, rows: np.ndarray | None) -> tuple[Any, Any, Any]:
        """The group's ``advance``, of these rows only (None: every robot)."""
        return self.group.advance(h) if rows is None else self.group.advance(h, rows)

    def coast(self, h: float, substeps: int, rows: np.ndarray | None) -> tuple[Any, Any, Any]:
        """The group's ``coast``, of these rows only (None: every robot)."""
        return (self.group.coast(h, substeps) if rows is None
                else self.group.coast(h, substeps, rows))
