"""Positions (of the centres of gravity) and velocities of a set of bodies, read (and set) for
a whole Space in one ``pymunk.batch`` call when that is cheaper than going through each body's
properties (a crowd: many bodies, each read costing a few microseconds of Python)."""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pymunk
import pymunk.batch as batch

_FIELDS = (batch.BodyFields.BODY_ID | batch.BodyFields.POSITION | batch.BodyFields.ANGLE
           | batch.BodyFields.VELOCITY)  # x, y, angle, vx, vy per body
PER_BODY_US = 3.0  # [us] reading one body's position and velocity through its properties
BATCH_US = 5.0  # [us] one batch call ...
BATCH_PER_BODY_US = 0.05  # [us] ... plus this per body in the space (measured, pymunk 7.3)


class BodyStates:
    """``read()``: an (n, 4) array of x, y [m] (centre of gravity), vx, vy [m/s] of
    ``bodies``, in their order; ``set_velocities``: theirs, in one batch call too."""

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body]) -> None:
        self.space = space
        self.bodies = list(bodies)
        self.ids = np.array([b.id for b in self.bodies], dtype=np.uintp)
        self.batched = bool(self.bodies) and (
            BATCH_US + BATCH_PER_BODY_US * len(space.bodies) < PER_BODY_US * len(self.bodies))
        self._buffer = batch.Buffer()
        self._out = batch.Buffer()
        self._rows: np.ndarray | None = None  # where our bodies are in the batch
        self._order = b""  # the batch's body ids when _rows was found
        self._take = np.zeros(0, dtype=np.intp)  # our x, y, vx, vy in the batch's floats
        self._space_state: np.ndarray | None = None  # every body's, at the last read
        cogs = np.array([tuple(b.center_of_gravity) for b in self.bodies]).reshape(-1, 2)
        self._cogs = cogs if cogs.any() else None  # [m] body frame, where not at the origin

    def read(self) -> np.ndarray:
        if not self.batched:
            return np.array([(*b.local_to_world(b.center_of_gravity), *b.velocity)
                             for b in self.bodies], dtype=float).reshape(-1, 4)
        self._buffer.clear()
        batch.get_space_bodies(self.space, _FIELDS, self._buffer)
        order = bytes(self._buffer.int_buf())
        state = np.frombuffer(self._buffer.float_buf(), dtype=float)
        self._space_state = state
        if order != self._order:
            # bodies were added or removed (a copy's reset on a shared ground): look again
            ids = np.frombuffer(order, dtype=np.uintp)
            sort = np.argsort(ids, kind="stable")
            rows = sort[np.searchsorted(ids[sort], self.ids)] if len(ids) else sort
            if len(rows) != len(self.ids) or not np.array_equal(ids[rows], self.ids):
                raise RuntimeError("a body read in a batch is no longer in the space")
            self._rows, self._order = rows, order
            self._take = (5 * rows[:, None] + np.array([0, 1, 3, 4])).ravel()
        mine = state.take(self._take).reshape(-1, 4)  # a copy, independent of the buffer
        if self._cogs is not None:  # from the body's origin to its centre of gravity
            assert self._rows is not None
            angle = state.take(5 * self._rows + 2)
            c, s = np.cos(angle), np.sin(angle)
            mine[:, 0] += c * self._cogs[:, 0] - s * self._cogs[:, 1]
            mine[:, 1] += s * self._cogs[:, 0] + c * self._cogs[:, 1]
        return mine

    def set_velocities(self, velocities: np.ndarray) -> None:
        """Give the first len(``velocities``) bodies ``velocities`` (k, 2) [m/s]. Batched,
        every other body of the space is given the velocity the last :meth:`read` saw: call it
        after a read, with no velocity set in between (in one actor's step)."""
        if not self.batched or self._space_state is None:
            for body, (vx, vy) in zip(self.bodies, velocities.tolist()):
                body.velocity = (vx, vy)
            return
        assert self._rows is not None
        every = self._space_state.reshape(-1, 5)[:, 3:].copy()
        every[self._rows[:len(velocities)]] = velocities
        self._out.clear()
        self._out.set_float_buf(every.tobytes())
        batch.set_space_bodies(self.space, batch.BodyFields.VELOCITY, self._out)
        self._space_state = None
