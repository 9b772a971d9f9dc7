"""Every LiDAR of a batch as rows: the scans due in a tick requested from one read of the
bodies, cast in one call of the ray caster and stored with the error model applied to all of
them at once.

A LiDAR alone (:meth:`Lidar.update`, :meth:`Lidar.scan`) and its row here give the same
floats: the origin is the body's position (Chipmunk's, read through ``pymunk.batch`` instead
of a property) or, for a LiDAR mounted off the body's origin, ``body.local_to_world``; the
beams' world angles are the body's angle plus the LiDAR's; the noise comes from each LiDAR's
own stream, in the same order, and ``true + std * noise`` is clipped operand for operand.
"""
from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from pymunk_bot.sensors.lidar import Lidar


class LidarRows:
    """``lidars``, each on the body whose pose is row ``robots[k]`` of the poses
    :meth:`scan` is given."""

    def __init__(self, lidars: Sequence[Lidar], robots: Sequence[int]) -> None:
        self.lidars = list(lidars)
        self._robot = np.asarray(robots, dtype=np.intp)
        # LiDARs off their body's origin: their origins come from body.local_to_world.
        self._mounted = {k for k, lidar in enumerate(self.lidars) if lidar.offset[:2] != (0.0, 0.0)}
        counts = {lidar.angles.shape[0] for lidar in self.lidars}
        # Beam angles in the body frame (K, n) when every LiDAR has as many beams.
        self._angles = np.stack([lidar.angles for lidar in self.lidars]) if len(counts) == 1 else None
        self._max_range = np.array([lidar.config.max_range for lidar in self.lidars])
        self._filters = [lidar.shape_filter for lidar in self.lidars]
        # ... as the caster's rows (group, categories, mask)
        self._filter_rows = np.array(self._filters, dtype=np.uint64).reshape(-1, 3)
        # (noise_std, min_range, max_range, dropout) per LiDAR
        self.models = np.array([lidar.model for lidar in self.lidars]).reshape(-1, 4)

    def requests(self, due: Sequence[int] | np.ndarray, poses: np.ndarray
                 ) -> tuple[np.ndarray, Any, np.ndarray, list]:
        """Where the ``due`` LiDARs cast from now: origins (K, 2) [m], world-frame beam angles
        [rad] ((K, n), or a list when the beam counts differ), max ranges (K,) [m] and
        filters, from ``poses`` (x, y, angle) of every body, (m, 3) [m, m, rad]."""
        rows = np.asarray(due, dtype=np.intp)
        pose = poses[self._robot[rows]]
        xy = pose[:, :2].copy()
        if self._mounted:
            for j, k in enumerate(rows.tolist()):
                if k in self._mounted:
                    xy[j] = self.lidars[k].origin()
        theta = pose[:, 2]
        if self._angles is not None:
            angles: Any = theta[:, None] + self._angles[rows]  # body.angle + angles, row by row
        else:
            angles = [t + self.lidars[k].angles for t, k in zip(theta.tolist(), rows.tolist())]
        return xy, angles, self._max_range[rows], [self._filters[k] for k in rows.tolist()]

    def scan(self, caster: Any, due: Sequence[int], times: Sequence[float],
             poses: Callable[[], np.ndarray]) -> None:
        """The ``due`` LiDARs (one or more) scan now: one ``caster.cast_many`` for all of them
        (their origins from ``poses()``: every body's (x, y, angle), read once), each scan
        stored as taken at its time in ``times`` [s]."""
        if len(due) == 1:  # one scan: the LiDAR's own (one body's pose, not every body's)
            lidar = self.lidars[due[0]]
            lidar.record(times[0], lidar.true_ranges())
            return
        rows = np.asarray(due, dtype=np.intp)
        self.store(due, times, caster.cast_many(*self.requests(rows, poses()),
                                                filter_rows=self._filter_rows[rows]))

    def store(self, due: Sequence[int], times: Sequence[float],
              true_ranges: Sequence[np.ndarray] | np.ndarray) -> None:
        """:meth:`Lidar.record` of each ``due`` LiDAR (at its time in ``times`` [s]) from its
        noise-free ranges [m]: the model's array work done once for all the noisy ones, and
        once for all the exact ones, that share a beam count."""
        lidars = [self.lidars[k] for k in due]
        if len(lidars) < 2 or not (isinstance(true_ranges, np.ndarray)  # one beam count: (K, n)
                                   or len({true.shape[0] for true in true_ranges}) == 1):
            for lidar, time, true in zip(lidars, times, true_ranges):
                lidar.record(time, true)
            return
        models = self.models[np.asarray(due, dtype=np.intp)]
        true = np.asarray(true_ranges)  # (K, n); read only below: no copy of the caster's rows
        noisy_rows = models[:, 0] > 0.0
        exact_rows = ~noisy_rows & (models[:, 3] == 0.0)
        for k in np.flatnonzero(~noisy_rows & ~exact_rows).tolist():  # dropout alone
            lidars[k].record(times[k], true_ranges[k])
        if exact_rows.any():  # the limits only, as a single scan's model
            exact = np.flatnonzero(exact_rows)
            ranges = np.minimum(true[exact], models[exact, 2:3])
            np.copyto(ranges, models[exact, 2:3], where=ranges < models[exact, 1:2])
            self._keep(lidars, times, exact.tolist(), ranges)
        if not noisy_rows.any():
            return
        noisy = np.flatnonzero(noisy_rows)
        if noisy.shape[0] < true.shape[0]:
            models, true = models[noisy], true[noisy]
        std, low, high = models[:, 0:1], models[:, 1:2], models[:, 2:3]
        ranges = np.empty_like(true)
        n = ranges.shape[1]
        which = noisy.tolist()
        for row, k in zip(ranges, which):
            row[:] = lidars[k].periodic_normals(n)
        ranges *= std  # the single scan's true + std * noise, operand for operand
        ranges += true
        np.maximum(ranges, low, out=ranges)
        np.minimum(ranges, high, out=ranges)
        no_return = true < low
        no_return |= true >= high
        dropout = models[:, 3]
        for j in np.flatnonzero(dropout > 0.0).tolist():
            no_return[j] |= lidars[which[j]].periodic_dropout(n, float(dropout[j]))
        np.copyto(ranges, high, where=no_return)  # high broadcast along each row
        self._keep(lidars, times, which, ranges)

    @staticmethod
    def _keep(lidars: list[Lidar], times: Sequence[float], which: list[int],
              ranges: np.ndarray) -> None:
        """Row j of ``ranges`` [m] (read-only from now on) is the scan of ``lidars[which[j]]``,
        taken at its time in ``times`` [s]."""
        ranges.setflags(write=False)
        for row, k in zip(ranges, which):
            lidars[k].keep(times[k], row)
