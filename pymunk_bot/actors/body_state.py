"""Positions and velocities of a set of bodies, read for a whole Space in one ``pymunk.batch``
call when that is cheaper than reading each body's properties (a crowd: many bodies, each
read costing a few microseconds of Python)."""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pymunk
import pymunk.batch as batch

_FIELDS = batch.BodyFields.BODY_ID | batch.BodyFields.POSITION | batch.BodyFields.VELOCITY
PER_BODY_US = 3.0  # [us] reading one body's position and velocity through its properties
BATCH_US = 5.0  # [us] one batch call ...
BATCH_PER_BODY_US = 0.05  # [us] ... plus this per body in the space (measured, pymunk 7.3)


class BodyStates:
    """``read()``: an (n, 4) array of x, y [m], vx, vy [m/s] of ``bodies``, in their order."""

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body]) -> None:
        self.space = space
        self.bodies = list(bodies)
        self.ids = np.array([b.id for b in self.bodies], dtype=np.uintp)
        self.batched = bool(self.bodies) and (
            BATCH_US + BATCH_PER_BODY_US * len(space.bodies) < PER_BODY_US * len(self.bodies))
        self._buffer = batch.Buffer()
        self._rows: np.ndarray | None = None  # where our bodies are in the batch

    def read(self) -> np.ndarray:
        if not self.batched:
            return np.array([(*b.position, *b.velocity) for b in self.bodies],
                            dtype=float).reshape(-1, 4)
        self._buffer.clear()
        batch.get_space_bodies(self.space, _FIELDS, self._buffer)
        ids = np.frombuffer(self._buffer.int_buf(), dtype=np.uintp)
        state = np.frombuffer(self._buffer.float_buf(), dtype=float).reshape(-1, 4)
        rows = self._rows
        if rows is None or len(ids) <= rows.max() or not np.array_equal(ids[rows], self.ids):
            # bodies were added or removed (a copy's reset on a shared ground): look again
            order = np.argsort(ids, kind="stable")
            rows = order[np.searchsorted(ids[order], self.ids)]
            if not np.array_equal(ids[rows], self.ids):
                raise RuntimeError("a body read in a batch is no longer in the space")
            self._rows = rows
        return state[rows]  # fancy indexing: a copy, independent of the buffer
