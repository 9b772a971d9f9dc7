"""The rays of one cast, sorted by angle, so an angle interval is an index range.

Intervals only choose which (primitive, ray) pairs get the exact test, with margins far
above rounding, so an index range that takes in a neighbouring ray is harmless.
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi
_TURNS = np.array([[-TWO_PI], [0.0], [TWO_PI]])


_ROTATIONS: dict[int, np.ndarray] = {}  # n -> arange(4 * n) % n, for Fan's rotations
_iota = np.arange(4096)


def iota(n: int) -> np.ndarray:
    """np.arange(n) as a view of a cached array (allocating one costs a call per cast)."""
    global _iota
    if n > _iota.shape[0]:
        _iota = np.arange(max(n, 2 * _iota.shape[0]))
    return _iota[:n]


class Rays:
    """Some of the rays, sorted by angle: the angles tiled over three turns, and the ray
    index of each entry. Any interval narrower than 2*pi inside [-3*pi, 3*pi) is then one
    index range with no ray repeated."""

    def __init__(self, theta: np.ndarray, ray: np.ndarray, ray3: np.ndarray | None = None) -> None:
        n = self.n = theta.shape[0]
        self.ray3 = np.concatenate((ray, ray, ray)) if ray3 is None else ray3
        self.grid: tuple[float, float, np.ndarray] | None = None
        if n >= 8:
            # An evenly spaced full turn (the usual LiDAR scan): entry j sits within err
            # steps of theta3[0] + j * step, so index ranges follow from arithmetic; a
            # binary search per interval mispredicts most branches and costs ~4x more.
            step = float(theta[-1] - theta[0]) / (n - 1)
            if step > 0.0:
                off = np.abs((theta - theta[0]) * (1.0 / step) - iota(n)).max()
                err = float(off) + 2.0 * abs(n * step - TWO_PI) / step + 1e-6
                if err < 0.25:
                    # (-err, err + 1): widen both ends; the + 1 makes stop exclusive.
                    self.grid = (float(theta[0] - TWO_PI), 1.0 / step, np.array(((-err,), (err + 1.0,))))
                    return
        self.theta3 = (theta + _TURNS).ravel()

    def ranges(self, lohi: np.ndarray, full: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """First entry and end entry (exclusive) of the rays inside each interval
        [lohi[0], lohi[1]] (every ray where full; None: nowhere).

        On a grid the range may include a ray within err steps outside the interval, which
        is harmless: intervals only choose which pairs get the exact test."""
        if self.grid is None:
            first = np.searchsorted(self.theta3, lohi[0], "left")
            stop = np.searchsorted(self.theta3, lohi[1], "right")
        else:
            t0, inv, widen = self.grid
            x = lohi - t0
            x *= inv
            x += widen
            np.maximum(x, 0.0, out=x)  # np.clip costs three times as much
            np.minimum(x, 3.0 * self.n, out=x)
            np.ceil(x[0], out=x[0])  # x >= 0, so astype's truncation floors x[1]
            first, stop = x.astype(np.intp)
        if full is not None:
            first[full] = self.n
            stop[full] = 2 * self.n
        return first, stop

    def expand(self, first: np.ndarray, stop: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ray index of every (interval, ray) pair, interval by interval; the number of
        pairs of each interval, and where each interval's pairs end."""
        counts = stop - first
        ends = np.cumsum(counts)
        # Pair j of interval i is entry first_i + (j - start_i) = j + (stop_i - ends_i).
        entry = np.repeat(stop - ends, counts)
        entry += iota(int(ends[-1]) if ends.shape[0] else 0)
        return self.ray3.take(entry), counts, ends


class Fan:
    """All rays of one cast: end points, and their direction angles in sorted order."""

    def __init__(self, theta: np.ndarray, ends: np.ndarray) -> None:
        n = theta.shape[0]
        self.ends = ends
        drops = np.flatnonzero(theta[1:] < theta[:-1])
        if drops.shape[0] <= 1 and (drops.shape[0] == 0 or theta[-1] <= theta[0]):
            # Sorted, or sorted but wrapping past +pi once (e.g. 0..2*pi): a rotation,
            # which is a slice of a cached arange(4 * n) % n.
            k = int(drops[0]) + 1 if drops.shape[0] else 0
            turns = _ROTATIONS.get(n)
            if turns is None:
                turns = np.arange(4 * n) % n
                if len(_ROTATIONS) < 16:
                    _ROTATIONS[n] = turns
            ray3 = turns[k:k + 3 * n]
            order = ray3[:n]
        else:
            order = np.argsort(theta, kind="stable")
            ray3 = None
        self.theta, self.order = theta.take(order), order
        self.every = Rays(self.theta, order, ray3)
        self.flagged: list[np.ndarray] = []  # rays passing near a flag (see cache.corner_flags)

    def open(self, best: np.ndarray, limit: float) -> Rays:
        """The rays whose current alpha exceeds limit."""
        pos = np.flatnonzero(best[self.order] > limit)
        return Rays(self.theta[pos], self.order[pos])
