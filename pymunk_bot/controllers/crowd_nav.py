"""What the crowd-navigation baselines (``social_force``, ``orca``) share: a global A* path on
the scenario's map, a look-ahead point on it, what the LiDAR sees as surface points (the
nearest return per angular sector, moving ones with their velocity from successive scans), and
turning a wished world-frame velocity into a command for the robot's drive.

Subclasses give :meth:`CrowdController.velocity`: the world-frame velocity [m/s] to drive at.
They see the crowd only through the LiDAR, as a real robot would.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.geometry.plane import wrap_angle
from pymunk_bot.planning.astar import astar
from pymunk_bot.planning.dwa import scan_points
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.planning.paths import shortcut
from pymunk_bot.planning.tracking import MovingObstacleTracker
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec

SECTORS = 36  # the nearest LiDAR return in each of this many sectors is an obstacle point
SENSE_RANGE = 4.0  # [m] farther returns are ignored
HEADING_GAIN = 2.5  # [1/s] yaw rate per radian of heading error
REPLAN_OFF_PATH = 1.0  # [m] farther than this from the path: plan again


class CrowdController(Controller):
    """A global path plus a local rule that picks the velocity (see the module doc)."""

    needs_map = True

    def __init__(self, config, robot: RobotSpec) -> None:
        super().__init__(config, robot)
        self.robot = robot
        self.grid: ClearanceGrid | None = None
        self.path: list[tuple[float, float]] | None = None
        self._goal: tuple[float, float] | None = None
        self.tracker = MovingObstacleTracker()
        self.last = np.zeros(2)  # the velocity asked last [m/s], world frame

    def set_map(self, world_map: MapInfo) -> None:
        self.map = world_map.without_movable()
        hard = self.robot.radius + self.config.margin
        self.grid = ClearanceGrid.from_map(self.map, self.config.resolution,
                                           cap=hard + 2 * self.config.resolution)

    def debug_path(self) -> list[tuple[float, float]] | None:
        return self.path

    def _plan(self, start: tuple[float, float], goal: tuple[float, float]) -> bool:
        assert self.grid is not None
        hard = self.robot.radius + self.config.margin
        plan = astar(self.grid, start, goal, hard=hard, soft=hard + 0.2, weight=2.0,
                     goal_radius=0.5)
        if plan.path is None:
            self.path = None
            self.message = plan.reason
            return False
        self.path = shortcut(self.grid, plan.path, hard)
        return True

    def carrot(self, xy: np.ndarray) -> np.ndarray:
        """The point ``lookahead`` [m] ahead along the path from its point nearest ``xy``."""
        assert self.path is not None
        pts = np.asarray(self.path, dtype=float)
        if len(pts) == 1:
            return pts[0]
        a, b = pts[:-1], pts[1:]
        ab = b - a
        length = np.maximum(np.hypot(*ab.T), 1e-12)
        u = np.clip(((xy - a) * ab).sum(axis=1) / length ** 2, 0.0, 1.0)
        near = a + u[:, None] * ab
        k = int(np.argmin(np.hypot(*(near - xy).T)))
        if float(np.hypot(*(near[k] - xy))) > REPLAN_OFF_PATH:
            self.path = None  # too far off: plan again from here
            return pts[-1]
        left = self.config.lookahead + u[k] * length[k]
        for j in range(k, len(ab)):
            if left <= length[j]:
                return a[j] + ab[j] * (left / length[j])
            left -= length[j]
        return pts[-1]

    def obstacles(self, obs: Observation) -> tuple[np.ndarray, np.ndarray]:
        """World-frame obstacle points (n, 2) [m] and their velocities (n, 2) [m/s]: the
        nearest return per sector within SENSE_RANGE."""
        scan = obs.scan
        if scan is None:
            return np.zeros((0, 2)), np.zeros((0, 2))
        points = scan_points(scan)
        x, y, theta = (float(v) for v in obs.pose[:3])
        speed = float(np.hypot(*self.last))
        velocities, _ = self.tracker.update(scan.time, obs.pose, points, speed,
                                            self.robot.radius + self.config.margin)
        if not len(points):
            return np.zeros((0, 2)), np.zeros((0, 2))
        dist = np.hypot(points[:, 0], points[:, 1])
        keep = dist <= SENSE_RANGE
        points, velocities, dist = points[keep], velocities[keep], dist[keep]
        sector = ((np.arctan2(points[:, 1], points[:, 0]) + math.pi) / (2 * math.pi)
                  * SECTORS).astype(int) % SECTORS
        order = np.lexsort((dist, sector))
        first = order[np.concatenate([[True], np.diff(sector[order]) != 0])] if len(order) \
            else order
        c, s = math.cos(theta), math.sin(theta)
        rotate = np.array([[c, -s], [s, c]])
        return points[first] @ rotate.T + (x, y), velocities[first] @ rotate.T

    @staticmethod
    def heading_to(xy: np.ndarray, carrot: np.ndarray) -> np.ndarray:
        """The unit vector from ``xy`` toward ``carrot`` (the preferred direction)."""
        to_carrot = carrot - xy
        return to_carrot / max(float(np.hypot(*to_carrot)), 1e-9)

    def velocity(self, xy: np.ndarray, carrot: np.ndarray, points: np.ndarray,
                 point_velocities: np.ndarray, period: float) -> np.ndarray:
        """The world-frame velocity [m/s] to drive at (subclasses)."""
        raise NotImplementedError

    def compute(self, obs: Observation) -> Command:
        goal = obs.goal
        if goal is None or self.grid is None:
            self.status, self.message = "failed", "no goal" if goal is None else "no map"
            return STOP
        goal = (float(goal[0]), float(goal[1]))
        xy = np.array([float(obs.pose[0]), float(obs.pose[1])])
        tolerance = self.config.tolerance if self.config.tolerance is not None \
            else obs.goal_tolerance
        if math.hypot(goal[0] - xy[0], goal[1] - xy[1]) <= 0.5 * tolerance:
            self.status, self.message = "arrived", ""
            self.last = np.zeros(2)
            return STOP
        if goal != self._goal or self.path is None:
            self._goal = goal
            if not self._plan((float(xy[0]), float(xy[1])), goal):
                return STOP
        self.status = "running"
        carrot = self.carrot(xy)
        points, point_velocities = self.obstacles(obs)
        period = 1.0 / self.rate
        wished = self.velocity(xy, carrot, points, point_velocities, period)
        speed = float(np.hypot(*wished))
        if speed > self.max_speed:
            wished = wished * (self.max_speed / speed)
        self.last = wished
        return self.to_command(obs.pose, wished)

    def to_command(self, pose, wished: np.ndarray) -> Command:
        """A world-frame velocity as this robot's command: an omni robot moves along it; the
        others turn toward it, going as fast as its part along the heading allows."""
        theta = float(pose[2])
        c, s = math.cos(theta), math.sin(theta)
        forward = c * wished[0] + s * wished[1]
        side = -s * wished[0] + c * wished[1]
        if self.robot.holonomic:
            return Command(forward, 0.0, side)
        if math.hypot(*wished) < 1e-6:
            return STOP
        error = wrap_angle(math.atan2(wished[1], wished[0]) - theta)
        omega = max(-self.robot.max_omega, min(self.robot.max_omega, HEADING_GAIN * error))
        return Command(max(forward, 0.0), omega)
