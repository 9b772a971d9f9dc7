"""When a sensor's period has come: due times on a fixed grid, so a rate never drifts."""
from __future__ import annotations

import math

# [s]; simulated times are sums of dt, so k * period can miss a tick by a rounding error
TIME_TOLERANCE = 1e-9


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
        self._next = 0  # index k of the next due time

    def due(self, time: float) -> bool:
        """True (and advance to the next due time) if a reading is due at ``time`` [s]."""
        if self.period is None:
            return True
        elapsed = time - self.start
        if elapsed + TIME_TOLERANCE < self._next * self.period:
            return False
        # Skip every due time this tick has already passed.
        self._next = math.floor((elapsed + TIME_TOLERANCE) / self.period) + 1
        return True
