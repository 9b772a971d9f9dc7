"""Leaving a stall: when the LiDAR vetoes every arc toward where a controller wants to go.

Beside an obstacle with the target behind it (or pressed against one after a manual override),
every arc toward the target is blocked and turning away scores worse than standing still, so
plain DWA freezes. After STALL_TIME of that, :class:`Escape` aims for a while at a point in the
free direction nearest to the target's bearing, fixed in the world, then hands back.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.planning.dwa import free_runs

STALL_SPEED = 0.02  # [m/s] commands slower than this count as stalled
STALL_TIME = 1.0  # [s] stalled before an escape
ESCAPE_DISTANCE = 0.8  # [m] how far an escape aims along the free direction it picks
ESCAPE_TIME = 3.0  # [s] an escape gives up after this
ESCAPE_REACHED = 0.25  # [m] closer than this to its point, an escape is over


class Escape:
    """Watches for stalls and, after STALL_TIME of one, picks a point to escape toward."""

    def __init__(self) -> None:
        self.stalled_since: float | None = None  # [s]
        self.point: tuple[float, float] | None = None  # world [m]
        self.until = 0.0  # [s] the escape gives up then

    def note(self, time: float, speed: float, wanted: float = math.inf) -> None:
        """The command just sent: ``speed`` [m/s] forward when ``wanted`` [m/s] was asked for
        (a stall is going slower than STALL_SPEED while wanting more)."""
        if speed > STALL_SPEED or wanted <= STALL_SPEED:
            self.stalled_since = None
        elif self.stalled_since is None:
            self.stalled_since = time

    def target(self, pose, time: float, points: np.ndarray, clearance: float,
               target: np.ndarray) -> np.ndarray | None:
        """The escape point in the robot frame while escaping, else None. ``points``: the
        scan in the robot frame; ``clearance`` [m]: the free corridor's half width;
        ``target``: where the robot wants to go, robot frame (the escape leaves toward it)."""
        if self.point is not None:
            local = to_robot_frame(pose, self.point)
            if time < self.until and float(np.hypot(*local)) > ESCAPE_REACHED:
                return local
            self.point = None
        if self.stalled_since is None or time - self.stalled_since < STALL_TIME:
            return None
        directions = np.linspace(-math.pi, math.pi, 72, endpoint=False)
        runs = free_runs(points, clearance, directions, ESCAPE_DISTANCE)
        open_ = runs >= 0.75 * ESCAPE_DISTANCE
        if not open_.any():
            return None
        bearing = math.atan2(float(target[1]), float(target[0]))
        off = np.abs((directions - bearing + np.pi) % (2 * np.pi) - np.pi)
        off[~open_] = np.inf
        direction = float(directions[int(np.argmin(off))])
        local = ESCAPE_DISTANCE * np.array([math.cos(direction), math.sin(direction)])
        x, y, theta = (float(v) for v in pose[:3])
        c, s = math.cos(theta), math.sin(theta)
        self.point = (x + c * local[0] - s * local[1], y + s * local[0] + c * local[1])
        self.until = time + ESCAPE_TIME
        self.stalled_since = None
        return local

    @property
    def active(self) -> bool:
        """Whether an escape is under way."""
        return self.point is not None


def to_robot_frame(pose, point) -> np.ndarray:
    """A world point in the frame of a robot at ``pose`` (x forward, y left)."""
    x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
    dx, dy = float(point[0]) - x, float(point[1]) - y
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * dx + s * dy, -s * dx + c * dy])
