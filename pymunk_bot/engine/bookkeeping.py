"""A run's bookkeeping after the physics, in one compiled pass over its robots.

Each robot's body position is read from Chipmunk (:mod:`pymunk_bot.physics.chipmunk`), its
path length grows by the step (``robots/progress.py``'s formula), and a differential drive's
plain encoders (ones that only scale) are dead-reckoned (``sensors/odometry.py``'s): the three
calls a tick made before, fused into one. A call from Python into compiled code costs about as
much as one robot's work, so for one robot the calls were the work. Each formula stays where it
was written; this pass only strings them together. Goals reached, and odometry of other drives
or of noisy encoders, follow through their own objects.
"""
from __future__ import annotations

from typing import Any, Sequence

import numba
import numpy as np

from pymunk_bot.physics.chipmunk import CALLS, GET_POSITION, get_vect
from pymunk_bot.physics.row_table import RowTable, floats_1d, floats_2d, integers_1d
from pymunk_bot.robots.drives.diff import DiffDriveGroup
from pymunk_bot.robots.progress import odometry_feed, travel_to
from pymunk_bot.robots.robot import Fleet
from pymunk_bot.sensors.odometry import DiffOdometryGroup, dead_reckon


# A bookkeeping table's slots (physics/row_table.py): Chipmunk's calls, the robots' bodies, the
# fleet's positions and distances; for the odometry reckoned in the same pass, a differential
# drive's wheel travel and its odometry's encoder scales, believed track, wheel travel, pose
# and mid-step factors.


@numba.njit(cache=True)
def travel_from_bodies(table: np.ndarray) -> None:
    """Each robot's body at its position now: the step from the fleet's last position added
    to its distance [m], the position kept (``table``'s first four slots)."""
    calls, bodies = integers_1d(table, 0), integers_1d(table, 1)
    last, distance = floats_2d(table, 2), floats_1d(table, 3)
    for i in range(bodies.shape[0]):
        x, y = get_vect(calls[GET_POSITION], bodies[i])
        travel_to(i, x, y, last, distance)


@numba.njit(cache=True)
def travel_and_reckon(table: np.ndarray) -> None:
    """:func:`travel_from_bodies`, then :func:`~pymunk_bot.sensors.odometry.dead_reckon` of a
    differential drive's accumulated wheel travel (zeroed once read)."""
    travel_from_bodies(table)
    dead_reckon(floats_2d(table, 4), floats_2d(table, 5), floats_1d(table, 6),
                floats_2d(table, 7), floats_2d(table, 8), floats_2d(table, 9), True)


class Bookkeeping:
    """After each tick: ``fleet``'s distance and goals from its robots' bodies (``bodies``,
    Chipmunk addresses in the fleet's order), and each (drive group, odometry group) of
    ``pairs`` dead-reckoned. The first differential drive with plain encoders is reckoned in
    the same compiled pass as the distance."""

    def __init__(self, fleet: Fleet, bodies: np.ndarray,
                 pairs: Sequence[tuple[Any, Any]]) -> None:
        self.fleet = fleet
        fused = [k for k, (drive, odometry) in enumerate(pairs)
                 if isinstance(drive, DiffDriveGroup) and isinstance(odometry, DiffOdometryGroup)
                 and odometry.plain]
        self.feeds = [odometry_feed(drive, odometry) for k, (drive, odometry) in enumerate(pairs)
                      if not fused or k != fused[0]]
        f64, intp = np.float64, np.intp
        slots: list[tuple[Any, str | None, Any, int]] = [
            (CALLS, None, intp, 1), (bodies, None, intp, 1),
            (fleet, "xy", f64, 2), (fleet, "distance", f64, 1)]
        if fused:
            drive, odometry = pairs[fused[0]]
            # the mid-step cos, sin, chord (read only by noisy encoders' propagation)
            mid = np.empty((3, odometry.pose.shape[0]))
            slots += [(drive, "travel", f64, 2), (odometry, "scale", f64, 2),
                      (odometry, "believed_track", f64, 1), (odometry, "wheel_travel", f64, 2),
                      (odometry, "pose", f64, 2), (mid, None, f64, 2)]
        self._pass = travel_and_reckon if fused else travel_from_bodies
        self._table = RowTable(slots)  # (it keeps the arrays it points to alive)

    def after_tick(self, now: Any) -> None:
        """The tick ending at ``now`` [s] (one for all, or each robot's as an array)."""
        self._pass(self._table.table)
        if self.fleet.goals_pending:
            self.fleet.arrive(now)
        if self.feeds:
            for feed in self.feeds:
                feed()
