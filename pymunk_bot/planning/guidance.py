"""Plan-guided goal features: where a learned policy is told to go when a global plan guides it.

A policy that sees one scan and the final goal's bearing cannot leave a room whose door lies
behind it. With guidance, the goal it sees is a point ``lookahead`` metres along an A* path
(:func:`~pymunk_bot.planning.astar.astar` on a clearance grid of the map the robot knows, then
:func:`~pymunk_bot.planning.paths.shortcut`, as the ``navigate`` controller plans):

- bearing: toward that lookahead point (the "carrot"), brought nearer along the path when the
  straight line to it would cross an obstacle on the map (it never points through a wall);
- distance: to the carrot plus the path's length beyond it, so it is the final goal's distance
  once the carrot reaches the goal, and shrinks with progress along the path before that.

The plan is made on the first observation of a goal and checked every ``replan_period``
(counted in observations, so the env and the ``policy`` controller check at the same ticks and
give bit-identical features): it is replanned when the robot is more than ``off_path`` from it
or when LiDAR returns the map does not explain lie on the path ahead (those returns are kept,
for FORGET_CHECKS checks after last seen, and planned around). When no path exists on the map
(the goal is unreachable, or the robot is boxed in), the features are the final goal's until a
later check finds one. The env (:mod:`pymunk_bot.envs.robot_task`) and the ``policy``
controller both use :class:`PlanGuide`; it reads nothing but the pose, the goal and the scan.
"""
from __future__ import annotations

import math

import numba
import numpy as np

from pymunk_bot.config.checks import too_many_cells
from pymunk_bot.config.guidance import PlanGuidanceConfig
from pymunk_bot.planning.astar import astar
from pymunk_bot.planning.grid import ClearanceGrid, segment_clearance
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.planning.paths import shortcut
from pymunk_bot.robots.readings import LaserScan

HARD_MARGIN = 0.02  # [m] beyond the robot's radius: closer cells are blocked (navigate's default)
SOFT_MARGIN = 0.25  # [m] beyond the radius: clearance paths keep where the room allows
CLEARANCE_COST = 4.0  # extra cost per metre next to an obstacle (navigate's default)
BLOCK_HORIZON = 3.0  # [m] of path ahead checked against unmapped returns
FORGET_CHECKS = 5  # an unmapped return not seen again for this many checks is forgotten
MAX_UNMAPPED = 4096  # unmapped cells kept at most (the oldest go first)
# Fractions of the lookahead tried, farthest first, for a carrot in line of sight (the last:
# the path point nearest the robot, taken whatever the line crosses)
CARROT_STEPS = (1.0, 0.75, 0.5, 0.25, 0.0)

Point = tuple[float, float]


class PlanGuide:
    """Goal features from a lookahead point on a global path, for one robot."""

    def __init__(self, settings: PlanGuidanceConfig, radius: float,
                 control_period: float) -> None:
        """``radius`` [m] of the robot; ``control_period`` [s] between observations."""
        self.settings = settings
        self.hard = radius + HARD_MARGIN  # [m]
        self.soft = radius + SOFT_MARGIN  # [m]
        self.check_every = max(1, round(settings.replan_period / control_period))  # observations
        self._map: MapInfo | None = None
        self._static: ClearanceGrid | None = None
        self.path: list[Point] | None = None  # the plan being followed (None: the final goal)
        self.plans = 0  # A* searches since the last restart
        self._goal: Point | None = None
        self._xy = np.zeros((1, 2))  # [m] the path's vertices
        self._cumulative = np.zeros(1)  # [m] path length up to each vertex
        self._segment = 0  # index of the path segment the robot was last nearest to
        self._until_check = 0  # observations before the next check
        self._checks = 0
        self._unmapped: dict[tuple[int, int], tuple[float, float, int]] = {}  # cell -> x, y, check

    def set_map(self, world_map: MapInfo) -> None:
        """Plan on this map (its movable obstacles left out: they may have been pushed); the
        grid is rasterised again only for a new map."""
        if world_map is self._map:
            return
        problem = too_many_cells(*world_map.size, self.settings.resolution)
        if problem is not None:
            raise ValueError(f"plan_guidance.resolution: {problem}")
        self._map = world_map
        cap = self.soft + 2.0 * self.settings.resolution
        self._static = ClearanceGrid.from_map(world_map.without_movable(),
                                              self.settings.resolution, cap)
        self.restart()

    def restart(self) -> None:
        """Forget the plan and the unmapped returns (a new episode or goal)."""
        self.path = None
        self.plans = 0
        self._goal = None
        self._until_check = 0
        self._checks = 0
        self._unmapped.clear()

    def features(self, x: float, y: float, theta: float, gx: float, gy: float,
                 scan: LaserScan | None) -> tuple[float, float, float]:
        """(distance [m], cos, sin of the bearing in the robot frame) of the guided goal seen
        from the pose (x, y, theta) heading for the goal (gx, gy); ``scan`` is the latest
        LiDAR scan (its unexplained returns trigger replans)."""
        if (gx, gy) != self._goal:
            self.restart()
            self._goal = (gx, gy)
        if self._until_check <= 0:
            self._until_check = self.check_every
            self._check(x, y, theta, gx, gy, scan)
        self._until_check -= 1
        tx, ty, beyond = (gx, gy, 0.0) if self.path is None else self._carrot(x, y)
        dx, dy = tx - x, ty - y
        bearing = math.atan2(dy, dx) - theta
        return math.sqrt(dx * dx + dy * dy) + beyond, math.cos(bearing), math.sin(bearing)

    # ------------------------------------------------------------------ planning
    def _check(self, x: float, y: float, theta: float, gx: float, gy: float,
               scan: LaserScan | None) -> None:
        """Remember unexplained returns; plan when there is no path, the robot strayed from
        it, or a return lies on it."""
        self._checks += 1
        if scan is not None:
            self._remember(x, y, theta, scan)
        if self.path is None or self._strayed(x, y) or self._blocked():
            self._plan(x, y, gx, gy)

    def _plan(self, x: float, y: float, gx: float, gy: float) -> None:
        static = self._grid()
        grid = static
        if self._unmapped:
            grid = static.copy()
            grid.add_points(np.array([(px, py) for px, py, _ in self._unmapped.values()]))
        self.plans += 1
        result = astar(grid, (x, y), (gx, gy), self.hard, self.soft, CLEARANCE_COST,
                       goal_radius=self.soft)
        if result.path is None:  # unreachable on what the robot knows: the final goal
            self.path = None
            return
        path = shortcut(grid, result.path, self.soft)
        if path[-1] != (gx, gy):  # a goal too close to a wall: the path ends beside it
            path.append((gx, gy))
        self.path = path
        self._xy = np.array(path, dtype=np.float64)
        steps = np.hypot(*np.diff(self._xy, axis=0).T)
        self._cumulative = np.concatenate([[0.0], np.cumsum(steps)])
        self._segment = 0

    def _grid(self) -> ClearanceGrid:
        if self._static is None:
            raise RuntimeError("plan guidance has no map: call set_map() first")
        return self._static

    def _strayed(self, x: float, y: float) -> bool:
        _, _, distance = self._nearest(x, y)
        return distance > self.settings.off_path

    def _blocked(self) -> bool:
        """Whether an unmapped return lies within the robot's radius of the path ahead."""
        if not self._unmapped or self.path is None:
            return False
        start = float(self._cumulative[self._segment])
        ahead = self._points_at(np.arange(start, min(start + BLOCK_HORIZON,
                                                     float(self._cumulative[-1])),
                                          0.5 * self.settings.resolution))
        if not len(ahead):
            return False
        points = np.array([(px, py) for px, py, _ in self._unmapped.values()])
        d2 = ((ahead[:, None, :] - points[None, :, :]) ** 2).sum(axis=2)
        return bool(d2.min() < self.hard ** 2)

    def _remember(self, x: float, y: float, theta: float, scan: LaserScan) -> None:
        """Keep the scan's returns that the map does not explain (a cell's clearance above
        two cells); forget those not seen for FORGET_CHECKS checks."""
        grid = self._grid()
        ranges = np.asarray(scan.ranges, dtype=float)
        hit = (ranges < scan.max_range) & (ranges >= scan.min_range) & np.isfinite(ranges)
        if hit.any():
            ox, oy, _ = scan.offset
            c, s = math.cos(theta), math.sin(theta)
            angles = np.asarray(scan.angles, dtype=float)[hit]
            lx, ly = ox + ranges[hit] * np.cos(angles), oy + ranges[hit] * np.sin(angles)
            wx, wy = x + c * lx - s * ly, y + s * lx + c * ly
            rows, cols = grid.cells_of(wx, wy)
            unexplained = grid.inside(wx, wy) & (grid.clearance[rows, cols]
                                                 > 2.0 * grid.resolution)
            for px, py, r, k in zip(wx[unexplained].tolist(), wy[unexplained].tolist(),
                                    rows[unexplained].tolist(), cols[unexplained].tolist()):
                self._unmapped.pop((r, k), None)  # re-inserted: the newest last
                self._unmapped[(r, k)] = (px, py, self._checks)
        stale = [cell for cell, (_, _, seen) in self._unmapped.items()
                 if self._checks - seen >= FORGET_CHECKS]
        for cell in stale:
            del self._unmapped[cell]
        while len(self._unmapped) > MAX_UNMAPPED:
            del self._unmapped[next(iter(self._unmapped))]

    # ------------------------------------------------------------------ along the path
    def _nearest(self, x: float, y: float) -> tuple[int, float, float]:
        """(segment, distance along the path [m], distance from the path [m]) of the path
        point nearest (x, y), from the segment last nearest on (progress does not go back)."""
        return nearest_on_path(self._xy, self._cumulative, self._segment, x, y)

    def _carrot(self, x: float, y: float) -> tuple[float, float, float]:
        """(x, y) [m] of the point ``lookahead`` along the path from the robot's nearest, or
        nearer if the straight line to it would cross the map's obstacles (a corner cut
        through a door frame); and the path's length beyond it [m]."""
        grid = self._grid()
        self._segment, tx, ty, beyond = carrot(
            self._xy, self._cumulative, self._segment, x, y, self.settings.lookahead,
            self.hard, grid.clearance, grid.origin[0], grid.origin[1], grid.size[0],
            grid.size[1], grid.resolution)
        return tx, ty, beyond

    def _points_at(self, distances: np.ndarray) -> np.ndarray:
        """Points [m] at these distances along the path, shape (n, 2)."""
        xy = np.asarray(self.path)
        return np.column_stack([np.interp(distances, self._cumulative, xy[:, 0]),
                                np.interp(distances, self._cumulative, xy[:, 1])])


@numba.njit(cache=True, nogil=True)
def nearest_on_path(xy: np.ndarray, cumulative: np.ndarray, first: int, x: float, y: float
                    ) -> tuple[int, float, float]:  # pragma: no cover - compiled
    """(segment, distance along [m], distance from the path [m]) of the point of the path
    ``xy`` (n x 2; ``cumulative``: its length up to each vertex) nearest (x, y), searched from
    segment ``first`` on (the first of equals)."""
    best_segment, best_along, best_distance = first, cumulative[first], np.inf
    for i in range(first, len(xy) - 1):
        ax, ay, bx, by = xy[i, 0], xy[i, 1], xy[i + 1, 0], xy[i + 1, 1]
        ex, ey = bx - ax, by - ay
        length2 = ex * ex + ey * ey
        t = 0.0 if length2 == 0 else min(1.0, max(0.0, ((x - ax) * ex + (y - ay) * ey)
                                                  / length2))
        distance = math.hypot(x - (ax + t * ex), y - (ay + t * ey))
        if distance < best_distance:
            best_segment, best_distance = i, distance
            best_along = cumulative[i] + t * math.sqrt(length2)
    return best_segment, best_along, best_distance


@numba.njit(cache=True, nogil=True)
def point_along(xy: np.ndarray, cumulative: np.ndarray, s: float
                ) -> tuple[float, float]:  # pragma: no cover - compiled
    """The point [m] ``s`` metres along the path (clamped to its ends; the last vertex
    exactly at its length)."""
    n = len(xy)
    if s >= cumulative[n - 1]:
        return xy[n - 1, 0], xy[n - 1, 1]
    i = 0
    while i < n - 2 and cumulative[i + 1] <= s:
        i += 1
    span = cumulative[i + 1] - cumulative[i]
    t = 0.0 if span <= 0 else max(0.0, (s - cumulative[i]) / span)
    return (xy[i, 0] + t * (xy[i + 1, 0] - xy[i, 0]), xy[i, 1] + t * (xy[i + 1, 1] - xy[i, 1]))


@numba.njit(cache=True, nogil=True)
def carrot(xy: np.ndarray, cumulative: np.ndarray, first: int, x: float, y: float,
           lookahead: float, hard: float, clearance: np.ndarray, ox: float, oy: float,
           width: float, height: float, resolution: float
           ) -> tuple[int, float, float, float]:  # pragma: no cover - compiled
    """(nearest segment, carrot x, y [m], path length beyond the carrot [m]) for the robot at
    (x, y): the point ``lookahead`` along the path from the robot's nearest, brought back by
    CARROT_STEPS until the straight line to it keeps ``hard`` clearance (or as much as the
    robot has now, less half a cell), on the grid ``clearance``."""
    segment, along, _ = nearest_on_path(xy, cumulative, first, x, y)
    total = cumulative[len(xy) - 1]
    rows, cols = clearance.shape
    col = min(cols - 1, max(0, math.floor((x - ox) / resolution)))
    row = min(rows - 1, max(0, math.floor((y - oy) / resolution)))
    need = min(hard, clearance[row, col]) - 0.5 * resolution
    ahead = min(total, along + lookahead) - along
    target, tx, ty = along, x, y
    for fraction in CARROT_STEPS:
        target = along + fraction * ahead
        tx, ty = point_along(xy, cumulative, target)
        if segment_clearance(clearance, ox, oy, width, height, resolution, x, y, tx, ty) >= need:
            break
    return segment, tx, ty, total - target
