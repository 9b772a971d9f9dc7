"""Scripted motion: a kinematic obstacle whose centre follows a polyline at constant speed.

Each tick the body gets the velocity that brings it exactly to where the script says it is at
the end of the tick, so its pose never drifts from the script, and pymunk pushes whatever is in
the way (a kinematic body has infinite mass).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pymunk_bot.physics.obstacles import Obstacle


class PathScript:
    """Where a point moving along ``path`` at ``speed`` [m/s] is at time t [s] (pure)."""

    def __init__(self, path: Sequence[Sequence[float]], speed: float, mode: str) -> None:
        points = np.asarray(path, dtype=float)
        if mode == "loop" and np.hypot(*(points[-1] - points[0])) > 1e-9:
            points = np.vstack([points, points[:1]])
        self.points = points
        self.cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])
        self.length = float(self.cum[-1])  # [m]
        self.speed = float(speed)
        self.mode = mode

    def arc_length(self, time: float) -> float:
        """Distance along the path [m] at ``time`` [s]."""
        travelled = self.speed * time
        if self.length <= 0:
            return 0.0
        if self.mode == "once":
            return min(travelled, self.length)
        if self.mode == "loop":
            return travelled % self.length
        phase = travelled % (2 * self.length)  # pingpong: there and back
        return phase if phase <= self.length else 2 * self.length - phase

    def position(self, time: float) -> np.ndarray:
        s = self.arc_length(time)
        return np.array([np.interp(s, self.cum, self.points[:, 0]),
                         np.interp(s, self.cum, self.points[:, 1])])


class ScriptedMotion:
    """Moves one obstacle along its ``motion`` script (an actor: ``before_step`` each tick)."""

    keeps_to_its_copy = True  # it moves its own obstacle only (a copy on a shared ground)

    def __init__(self, obstacle: Obstacle) -> None:
        motion: Any = getattr(obstacle.config, "motion")
        self.obstacle = obstacle
        self.script = PathScript(motion.path, motion.speed, motion.mode)
        # The script moves the obstacle's centre; its first point is where the centre starts.
        self.offset = np.asarray(obstacle.body.position) - self.script.points[0]
        self.angular_speed = motion.angular_speed  # [rad/s]
        self.angle0 = obstacle.body.angle

    def before_step(self, time: float, dt: float) -> None:
        body = self.obstacle.body
        target = self.script.position(time + dt) + self.offset
        x, y = body.position
        body.velocity = ((target[0] - x) / dt, (target[1] - y) / dt)
        angle = self.angle0 + self.angular_speed * (time + dt)
        body.angular_velocity = (angle - body.angle) / dt

