"""Bodies as rows: one ``pymunk.batch`` read per Space, and writes back.

The engine's one reader of many bodies: Propulsion reads every body of its Space (or of two:
the contact Space, and the one where robots nothing can reach step apart, physics/apart.py)
and writes control bodies back, each through one batch call per Space; the substep gate reads
its movers' motion the same way. Rows are pymunk's body order, the contact Space's first;
where each body and control body sits is looked up again whenever bodies come, go or move
between the Spaces. A few bodies are read one by one through Chipmunk's getters instead.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pymunk
import pymunk.batch as batch

# A few robots' bodies are read one by one each tick through Chipmunk's own getters on their
# handles (what pymunk's properties call; ``pymunk.cp`` is Chipmunk's library): a quarter of a
# property's cost, which builds a Vec2d on every read. pymunk gives the handle no public name.
get_position = pymunk.cp.cpBodyGetPosition
get_angle = pymunk.cp.cpBodyGetAngle
get_spin = pymunk.cp.cpBodyGetAngularVelocity
get_velocity = pymunk.cp.cpBodyGetVelocity


def handles(bodies: Sequence[pymunk.Body]) -> list:
    """Chipmunk's handle of each body, for :data:`get_position`, :data:`get_angle`,
    :data:`get_spin` and :data:`get_velocity` (valid while the body lives)."""
    return [body._body for body in bodies]


class BodyRows:
    """The bodies of ``space`` (and of a second Space, once :meth:`add` names it) as rows;
    ``robot`` and ``control``: the rows of ``bodies`` and ``controls``; ``out`` (velocity and
    spin) and ``held_out`` (angle, velocity, spin): rows to write back, one per body."""

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body],
                 controls: Sequence[pymunk.Body]) -> None:
        self.spaces = [space]
        self._n = len(bodies)
        # pymunk's ids of the bodies, then of the control bodies (to find their rows)
        self._ids = np.array([b.id for b in list(bodies) + list(controls)], dtype=np.uintp)
        self._reads = [batch.Buffer()]
        self._writes = [batch.Buffer()]
        self._held_writes = [batch.Buffer()]
        self._bounds = [0, 0]  # each Space's first row, and the end
        self._rows = -1  # bodies the last lookup was made for (-1: look again)
        self._counts: list[int] = []  # ... in each Space
        self.robot = self.control = np.zeros(0, dtype=np.intp)
        self.out = np.zeros((0, 3))
        self.held_out = np.zeros((0, 4))

    def add(self, space: pymunk.Space) -> None:
        """Read ``space``'s bodies too, after the first Space's."""
        self.spaces.append(space)
        self._reads.append(batch.Buffer())
        self._writes.append(batch.Buffer())
        self._held_writes.append(batch.Buffer())
        self._rows = -1

    def relocated(self) -> None:
        """Bodies moved between the Spaces: where each sits is looked up at the next read."""
        self._rows = -1

    def read(self, fields: batch.BodyFields, width: int, first_only: bool = False
             ) -> np.ndarray:
        """Every body's ``fields`` (``width`` floats each), the first Space's rows first
        (``first_only``: its rows alone, for robots known to be there)."""
        rows = self.read_every(fields, width)
        if len(self.spaces) == 1:
            if rows.shape[0] != self._rows:
                self._look_up([rows.shape[0]])
            return rows
        if first_only and self._rows >= 0 and rows.shape[0] == self._counts[0]:
            return rows
        other = self._reads[1]
        other.clear()
        batch.get_space_bodies(self.spaces[1], fields, other)
        apart = np.frombuffer(other.float_buf()).reshape(-1, width)
        counts = [rows.shape[0], apart.shape[0]]
        if self._rows < 0 or counts != self._counts:  # bodies came, went or moved Space
            self._look_up(counts)
        return np.concatenate([rows, apart]) if apart.shape[0] else rows

    def read_every(self, fields: batch.BodyFields, width: int) -> np.ndarray:
        """Every body of the first Space's ``fields`` (``width`` floats each), whoever is in
        it: no rows are looked up."""
        buffer = self._reads[0]
        buffer.clear()
        batch.get_space_bodies(self.spaces[0], fields, buffer)
        return np.frombuffer(buffer.float_buf()).reshape(-1, width)

    def write(self, fields: batch.BodyFields, held: bool = False,
              spaces: slice = slice(None)) -> None:
        """Write ``out`` (``held``: ``held_out``) back as ``fields``, to every Space or to
        those of ``spaces``."""
        buffers = self._held_writes if held else self._writes
        if len(self.spaces) == 1:
            batch.set_space_bodies(self.spaces[0], fields, buffers[0])
            return
        for k in range(len(self.spaces))[spaces]:
            if self._bounds[k + 1] > self._bounds[k]:
                batch.set_space_bodies(self.spaces[k], fields, buffers[k])

    def _look_up(self, counts: list[int]) -> None:
        """Where each body and control body sits in the rows (``counts``: the bodies of each
        Space), and output rows to match."""
        found = []
        for space in self.spaces:
            ids = batch.Buffer()
            batch.get_space_bodies(space, batch.BodyFields.BODY_ID, ids)
            found.append(np.frombuffer(ids.int_buf(), dtype=np.uintp))
        every = np.concatenate(found)
        by_id = np.argsort(every, kind="stable")
        rows_of = by_id[np.searchsorted(every[by_id], self._ids)]
        self.robot, self.control = rows_of[:self._n], rows_of[self._n:]
        self._bounds = np.concatenate([[0], np.cumsum(counts)]).tolist()
        rows = self._bounds[-1]
        self.out = np.zeros((rows, 3))
        self.held_out = np.zeros((rows, 4))
        for k, (start, stop) in enumerate(zip(self._bounds, self._bounds[1:])):
            if stop > start:
                self._writes[k].set_float_buf(self.out[start:stop])
                self._held_writes[k].set_float_buf(self.held_out[start:stop])
        self._rows, self._counts = rows, list(counts)
