"""When a sensor's period has come: due times on a fixed grid, so a rate never drifts."""
from __future__ import annotations

import math

import numpy as np

# [s]; simulated times are sums of dt, so k * period can miss a tick by a rounding error
TIME_TOLERANCE = 1e-9
SMALL_ARRAY = 24  # below this many schedules, ScheduleArray asks each one


class Schedule:
    """Due times ``start + k / rate`` for k = 0, 1, 2, ...; ``rate=None`` means every call.

    A sensor's reading is taken on the first simulation tick at or after each due time, so a
    10 Hz sensor in a 60 Hz simulation reads on every 6th tick and one faster than the
    simulation reads once per tick (due times that fall inside one tick are merged).
    """

    def __init__(self, rate: float | None, start: float = 0.0) -> None:
        if rate is not None and not (math.isfinite(rate) and rate > 0):
            raise ValueError(f"rate must be a finite number > 0 (got {rate})")
        self.period = None if rate is None else 1.0 / rate  # [s]
        self.start = start  # [s]
        self.next_index = 0  # index k of the next due time

    def due(self, time: float) -> bool:
        """True (and advance to the next due time) if a reading is due at ``time`` [s]."""
        if self.period is None:
            return True
        elapsed = time - self.start
        if elapsed + TIME_TOLERANCE < self.next_index * self.period:
            return False
        # Skip every due time this tick has already passed.
        self.next_index = math.floor((elapsed + TIME_TOLERANCE) / self.period) + 1
        return True


class ScheduleArray:
    """Many schedules checked at once: the same due rule as :class:`Schedule`, as arrays.

    Built from existing schedules (taking over their state); their own ``due`` must not be
    called afterwards."""

    def __init__(self, schedules: list[Schedule]) -> None:
        self._each = schedules if len(schedules) < SMALL_ARRAY else None
        self.period = np.array([np.inf if s.period is None else s.period for s in schedules])
        self.every_tick = np.array([s.period is None for s in schedules], dtype=bool)
        self.start = np.array([s.start for s in schedules], dtype=float)
        # index k of each one's next due time
        self.next = np.array([s.next_index for s in schedules], dtype=float)
        self.earliest = self._first_due()  # [s] nothing is due before this

    def _first_due(self) -> float:
        """The earliest time [s] anything is due (so most ticks need no array work)."""
        if self.every_tick.any():
            return -np.inf
        if self.next.shape[0] == 0:
            return np.inf
        return float((self.start + self.next * self.period).min())

    def due(self, time: float) -> list[int]:
        """Indices of the schedules due at ``time`` [s] (each then advances to its next due time)."""
        if time + TIME_TOLERANCE < self.earliest:  # most ticks: nothing due
            return []
        if self._each is not None:  # a few: the schedules themselves are cheaper than numpy
            hits = [k for k, schedule in enumerate(self._each) if schedule.due(time)]
            self.earliest = min((s.start + s.next_index * s.period if s.period is not None
                                 else -math.inf for s in self._each), default=math.inf)
            return hits
        elapsed = time - self.start + TIME_TOLERANCE
        due = self.every_tick | (elapsed >= self.next * np.where(self.every_tick, 0.0, self.period))
        index = np.flatnonzero(due)
        finite = index[~self.every_tick[index]]
        self.next[finite] = np.floor(elapsed[finite] / self.period[finite]) + 1
        self.earliest = self._first_due()
        return index.tolist()
