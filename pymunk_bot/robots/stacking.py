"""Copies of one scenario bookkept in one pass: the copies' fleets, drive groups and odometry
each as one group over the rows every copy holds (copy 0's robots first).

The copies are built on :class:`~pymunk_bot.robots.rows.SharedRows`: each copy's groups keep
their per-robot fields (``ROWS``) in its block of shared arrays from birth, and a group here
holds the whole arrays (a class opts in by naming ``ROWS`` and giving ``stacked(parts, rows)``,
which builds the whole from the parts' configs on those rows). Each copy keeps its own objects,
and its robots' handles read them: a write on either side is seen by both, and nothing is
rebound when a copy is rebuilt.

Per-tick work on the stack (coast, travel, odometry, distance and goals: engine/bookkeeping.py
for the last three) does the arithmetic a copy's own objects do on their rows, operation for
operation, so the floats are the same.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pymunk_bot.robots.rows import SharedRows


class Stack:
    """The fleets, drive groups and odometry groups of ``sims`` (copies of one scenario, built
    on ``shared``), each as one over every copy's rows; see :meth:`of`."""

    def __init__(self, sims: Sequence[Any], shared: SharedRows) -> None:
        whole = shared.whole()
        fleets = [sim.built.fleet for sim in sims]
        self.fleet = type(fleets[0]).stacked(fleets, whole.of_fleet())
        self.per_copy = len(sims[0].robots)  # robots of each copy
        slots = len(sims[0].built.drive_groups)
        # Each whole, with its robots' indices and the first row of each copy's part.
        self.drive_groups: list[tuple[Any, list[int], list[int]]] = []
        self.pairs: list[tuple[Any, Any]] = []  # (drive group, its odometry), stacked
        for j in range(slots):
            drives = [sim.built.drive_groups[j][0] for sim in sims]
            odometries = [sim.built.odometry_groups[j][0] for sim in sims]
            kind = drives[0].configs[0].drive  # the name its rows are kept under (build.py)
            members = [copy * self.per_copy + i for copy, sim in enumerate(sims)
                       for i in sim.built.drive_groups[j][1]]
            starts = np.cumsum([0] + [part.n for part in drives[:-1]]).tolist()
            drive = type(drives[0]).stacked(drives, whole.of_drive(kind))
            self.drive_groups.append((drive, members, starts))
            self.pairs.append((drive, type(odometries[0]).stacked(
                odometries, whole.of_odometry(kind))))
        # Robot (copy * per_copy + index in its copy) -> (its stacked drive group, its row).
        self.row_of = {robot: (whole, row) for whole, members, _ in self.drive_groups
                       for row, robot in enumerate(members)}

    @classmethod
    def of(cls, sims: Sequence[Any], shared: SharedRows) -> "Stack | None":
        """The stack of these copies (built on ``shared``), or None if some group cannot be
        stacked (its class names no ``ROWS``) or a copy has no robots."""
        first = sims[0].built
        groups = [first.fleet] + [g for g, _ in first.drive_groups + first.odometry_groups]
        if not first.robots or not all(getattr(type(g), "ROWS", ()) for g in groups):
            return None
        return cls(sims, shared)


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
