"""Where each LiDAR scan was taken from, for controllers that remember what their scans show.

A controller is handed the LiDAR's latest scan on every tick. A LiDAR slower than the
controller (5 Hz under a 10 Hz controller) hands it the same scan on two ticks or more; placed
with the later tick's pose, a robot turning at a few rad/s puts the scan tens of degrees off
and copies the room's walls around itself as "unmapped obstacles" (docs/localization-journal.md,
"navigate: its own scans placed with a later pose"). :class:`ScanPoses` says which scan is new
and the pose estimate at its time.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.controllers.base import Observation

MAX_GAP = 1.5  # [control periods] older previous poses are not interpolated from


class ScanPoses:
    """Each scan once, with the pose estimate interpolated to the time it was taken."""

    def __init__(self, rate_hz: float) -> None:
        self.period = 1.0 / rate_hz  # [s] between the controller's ticks
        self._scan_time: float | None = None  # [s] of the last scan handed out
        self._last: tuple[float, np.ndarray] | None = None  # (time [s], pose) of the last tick

    def new_scan_pose(self, obs: Observation) -> np.ndarray | None:
        """The pose [x, y, theta] the robot took ``obs.scan`` from, or None when there is no
        scan or it was handed out before. Call it on every tick (it keeps this tick's pose)."""
        pose = None
        scan = obs.scan
        if scan is not None and scan.time != self._scan_time:
            self._scan_time = scan.time
            pose = self.pose_at(scan.time, obs)
        self._last = (obs.time, np.asarray(obs.pose, dtype=float))
        return pose

    def pose_at(self, when: float, obs: Observation) -> np.ndarray:
        """The pose estimate at ``when`` [s] (at or before ``obs.time``): interpolated between
        the previous tick's estimate and this one's, the previous one's if older. Without a
        previous tick just before (the first, or after ticks that stopped early), this one's."""
        now = np.asarray(obs.pose, dtype=float)
        last = self._last
        if (last is None or when >= obs.time or last[0] >= obs.time
                or obs.time - last[0] > MAX_GAP * self.period):
            return now
        then, before = last
        if when <= then:
            return before
        f = (when - then) / (obs.time - then)
        turn = math.remainder(float(now[2] - before[2]), math.tau)  # [rad] the shorter way
        return np.array([before[0] + f * (now[0] - before[0]), before[1] + f * (now[1] - before[1]),
                         before[2] + f * turn])
