"""``navigate`` for a car-like robot: Hybrid A* on the map, then pure pursuit segment by segment.

The planner (:mod:`pymunk_bot.planning.hybrid_astar`) finds a path the car can drive, with its
real footprint checked along every arc, that may back up. The path is cut where the direction
changes; each segment is followed with pure pursuit (in reverse, with the rear as the front),
braking to a stop at its end before the next begins. Off the path or without progress for
``stuck_time`` it replans from where it is. With a LiDAR, scan returns the map does not explain
are remembered for a while (each scan once, placed with the pose estimate of its time:
pymunk_bot.controllers.scan_pose); when they lie on the next 0.6 m of the path (checked with the
footprint, as the planner does) the car stops, and after a moment plans around them.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.config.controllers import NavigateControllerConfig
from pymunk_bot.geometry.footprint import Footprint
from pymunk_bot.geometry.plane import wrap_angle
from pymunk_bot.planning.dwa import scan_points
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.hybrid_astar import FootprintChecker, HybridParams, HybridResult, hybrid_astar
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.planning.pursuit import PathTracker, PursuitGains
from pymunk_bot.planning.steering import car_pursue
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec
from pymunk_bot.controllers.scan_pose import ScanPoses

OFF_PATH = 0.5  # [m] farther than this from the segment: replan
SEGMENT_END = 0.08  # [m] a segment is done this close to its end
BLOCK_LOOKAHEAD = 0.6  # [m] of path ahead checked against returns the map does not explain
MIN_LOOKAHEAD = 0.3  # [m]
UNMAPPED_RANGE = 4.0  # [m] scan returns the map does not explain are remembered this close
UNMAPPED_MEMORY = 10.0  # [s] and forgotten this long after they were last seen
MAX_UNMAPPED = 5000  # remembered cells at most (the oldest go first)
BLOCKED_REPLAN = 1.5  # [s] stopped by something unmapped before planning around it
RETRY_PERIOD = 1.0  # [s] between replans while unmapped things block every route


class CarNavigateController(Controller):
    """Plans drivable paths for an ackermann robot and follows them, forward and reverse."""

    needs_map = True

    def __init__(self, config: NavigateControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config, robot)
        self.robot = robot
        h = config.hybrid
        self.params = HybridParams(step=h.step, heading_bins=h.heading_bins, reverse=h.reverse,
                                   reverse_cost=h.reverse_cost, switch_cost=h.switch_cost,
                                   max_expansions=h.max_expansions, margin=config.hard_margin)
        footprint: Footprint | None = robot.footprint
        if footprint is None:
            self.discs = (np.zeros((1, 2)), np.array([robot.radius]))
        else:
            self.discs = footprint.covering_discs(h.disc_spacing)
        self.gains = PursuitGains(lookahead=config.lookahead, max_speed=self.max_speed,
                                  lateral_accel=config.pursuit.lateral_accel,
                                  decel=config.pursuit.decel, rotate_threshold=math.pi,
                                  track_width=0.0, corner_radius=0.0)
        self.checker: FootprintChecker | None = None
        self.plan: HybridResult | None = None
        self.segments: list[tuple[int, PathTracker]] = []
        self.replans = 0
        self._goal: tuple[float, float] | None = None
        self._progress = (0.0, 0.0)  # (progress along the segment [m], when [s])
        self._failed = False
        self.unmapped: dict[tuple[int, int], tuple[float, float, float]] = {}  # cell -> x, y, t
        self._blocked_since: float | None = None
        self._waiting_since: float | None = None
        self._next_retry = 0.0
        # A LiDAR slower than the controller hands it the same scan on several ticks: each is
        # remembered once, with the pose it was taken from (a tight turn moves the pose ~10 deg
        # a tick: the walls copied beside themselves, stopping the car).
        self.scan_poses = ScanPoses(self.rate)

    def set_map(self, world_map: MapInfo) -> None:
        self.map = world_map if self.config.map_movable else world_map.without_movable()
        cap = float(self.discs[1].max()) + self.config.margin + 3 * self.config.resolution
        self.grid = ClearanceGrid.from_map(self.map, self.config.resolution, cap)
        self.checker = FootprintChecker(self.grid, *self.discs, self.params.margin)

    def debug_path(self):
        if self.plan is None or not self.plan.found:
            return None
        return [tuple(p) for p in self.plan.poses[:, :2].tolist()]

    # ------------------------------------------------------------------ control
    def compute(self, obs: Observation) -> Command:
        goal = obs.goal
        if goal is None:
            return self._fail("no goal: set controller.goal or the robot's goal")
        if self.checker is None:
            return self._fail("no map (the simulation did not call set_map)")
        goal = (float(goal[0]), float(goal[1]))
        if goal != self._goal:
            self._goal, self.segments, self._failed = goal, [], False
            self.watch.restart()
        if self._failed:
            return STOP
        taken_from = self.scan_poses.new_scan_pose(obs)
        if taken_from is not None:
            self._remember(obs, taken_from)
        tolerance = self.config.tolerance if self.config.tolerance is not None else obs.goal_tolerance
        pose = np.asarray(obs.pose, dtype=float)
        if self._arrived(pose, goal, tolerance) and (not self.segments or len(self.segments) == 1
                                                     and self.segments[0][1].remaining() < 0.1):
            self.status, self.message = "arrived", ""
            return STOP
        if not self.segments and (obs.time < self._next_retry or not self._plan(
                pose, goal, tolerance, obs.time, around_unmapped=self._waiting_since is not None)):
            return STOP
        direction, tracker = self.segments[0]
        x, y = float(pose[0]), float(pose[1])
        tracker.update(x, y, window=1.0)
        if math.dist(tracker.point_at(tracker.s), (x, y)) > OFF_PATH or (
                obs.time - self._progress[1] > self.config.stuck_time):
            if not self._plan(pose, goal, tolerance, obs.time):
                return STOP
            direction, tracker = self.segments[0]
            tracker.update(x, y, window=1.0)
        if tracker.s > self._progress[0] + 0.05:
            self._progress = (tracker.s, obs.time)
        if self.gave_up(obs, tracker.s):  # along any segment: replans do not reset it
            return self._fail(f"{self.message} after {self.replans} plans")
        end = tracker.points[-1]
        if tracker.remaining() < SEGMENT_END or math.dist(end, (x, y)) < SEGMENT_END:
            self.segments.pop(0)
            self._progress = (0.0, obs.time)
            self.watch.mark(obs.time, 0.0)  # a segment's end is progress; the next from 0
            if not self.segments:
                return STOP
            return STOP  # stop for a tick before driving the other way
        if self._blocked(pose):
            if self._blocked_since is None:
                self._blocked_since = obs.time
            if obs.time - self._blocked_since < BLOCKED_REPLAN:
                self.message = "stopped: something not on the map is in the way"
                return STOP
            self._blocked_since = None
            self.segments = []
            self._plan(pose, goal, tolerance, obs.time, around_unmapped=True)
            return STOP
        self._blocked_since = None
        self.status = "running"
        speed = max(tracker.speed_at(tracker.s), self.gains.min_speed)
        to_end = math.dist(end, (x, y))
        speed = min(speed, math.sqrt(2.0 * self.gains.decel * to_end) + 0.05)
        lookahead = max(MIN_LOOKAHEAD, min(self.gains.lookahead, self.gains.lookahead_time * speed))
        carrot = tracker.point_at(tracker.s + lookahead)
        if tracker.remaining() <= lookahead:  # aim past the end along its heading
            carrot = end + (lookahead - tracker.remaining()) * direction * np.array(
                [math.cos(self._end_heading), math.sin(self._end_heading)])
        return car_pursue(pose, carrot, speed, self.robot.min_turn_radius, reverse=direction < 0)

    def _arrived(self, pose, goal, tolerance: float) -> bool:
        if math.hypot(goal[0] - pose[0], goal[1] - pose[1]) > tolerance:
            return False
        heading = self.config.heading
        return heading is None or abs(wrap_angle(pose[2] - heading)) <= 1.5 * self.config.heading_tolerance

    # ------------------------------------------------------------------ planning
    def _plan(self, pose, goal, tolerance: float, now: float, around_unmapped: bool = False) -> bool:
        """Plan from ``pose``; ``around_unmapped``: with the remembered scan returns on the map.
        No path on the map itself fails at once; no path only around unmapped things is
        retried every RETRY_PERIOD until ``give_up_after``."""
        self.replans += 1
        if self.checker is None:
            return False
        checker = self._unmapped_checker() if around_unmapped else self.checker
        if checker is None:  # only without a map checker, handled above
            return False
        smallest = float(self.discs[1].min())
        self.plan = hybrid_astar(checker, pose, goal, 0.5 * tolerance,
                                 self.robot.min_turn_radius, self.params, self.config.heading,
                                 self.config.heading_tolerance, heuristic_clearance=smallest)
        if not self.plan.found:
            if checker is self.checker or checker is None:
                self._fail(f"{self.plan.reason} on the map (plan {self.replans})")
                return False
            if self._waiting_since is None:
                self._waiting_since = now
            waited = now - self._waiting_since
            if waited >= self.config.give_up_after:
                self._fail(f"no drivable path: things that are not on the map have blocked every "
                           f"route for {waited:.0f} s")
                return False
            self.segments = []
            self._next_retry = now + RETRY_PERIOD
            self.message = f"waiting: things not on the map block every route ({waited:.0f} s)"
            return False
        self._waiting_since = None
        self.segments = [(d, PathTracker([tuple(p) for p in poses[:, :2]], False, self.gains))
                         for d, poses in self.plan.segments() if len(poses) >= 2]
        self._segment_poses = [poses for _, poses in self.plan.segments() if len(poses) >= 2]
        self._progress = (0.0, now)
        self.watch.rebase(0.0)  # progress along the new plan counts; the clock runs on
        self.message = (f"following a {len(self.segments)}-segment drivable path "
                        f"(plan {self.replans}, {self.plan.expansions} expansions)")
        return bool(self.segments)

    @property
    def _end_heading(self) -> float:
        poses = self._segment_poses[len(self._segment_poses) - len(self.segments)]
        return float(poses[-1, 2])

    def _remember(self, obs: Observation, taken_from: np.ndarray) -> None:
        """Keep the returns of ``obs.scan`` the map does not explain (world frame, the scan
        placed at ``taken_from`` [x, y, theta]), for a while."""
        if obs.scan is None:
            raise ValueError("_remember needs an observation with a LiDAR scan")
        points = scan_points(obs.scan)
        now = obs.time
        for key in [k for k, (_, _, t) in self.unmapped.items() if now - t > UNMAPPED_MEMORY]:
            del self.unmapped[key]
        if not len(points):
            return
        points = points[np.hypot(points[:, 0], points[:, 1]) < UNMAPPED_RANGE]
        x, y, theta = (float(v) for v in taken_from[:3])
        c, s = math.cos(theta), math.sin(theta)
        wx, wy = x + c * points[:, 0] - s * points[:, 1], y + s * points[:, 0] + c * points[:, 1]
        g = self.grid
        inside = (wx > 0) & (wy > 0) & (wx < g.size[0]) & (wy < g.size[1])
        cols = np.clip((wx / g.resolution).astype(int), 0, g.cols - 1)
        rows = np.clip((wy / g.resolution).astype(int), 0, g.rows - 1)
        new = inside & (g.clearance[rows, cols] > 2.0 * g.resolution)
        for px, py, r, k in zip(wx[new].tolist(), wy[new].tolist(), rows[new].tolist(),
                                cols[new].tolist()):
            self.unmapped.pop((r, k), None)
            self.unmapped[(r, k)] = (px, py, now)
        while len(self.unmapped) > MAX_UNMAPPED:
            del self.unmapped[next(iter(self.unmapped))]

    def _unmapped_checker(self) -> FootprintChecker | None:
        """The footprint checker of the map plus the remembered unmapped returns."""
        if not self.unmapped or self.checker is None:
            return self.checker
        grid = self.grid.copy()
        grid.add_points(np.array([(x, y) for x, y, _ in self.unmapped.values()]))
        return FootprintChecker(grid, *self.discs, self.params.margin)

    def _blocked(self, pose: np.ndarray) -> bool:
        """The next BLOCK_LOOKAHEAD metres of the segment collide with unmapped returns."""
        if not self.unmapped:
            return False
        poses = self._segment_poses[len(self._segment_poses) - len(self.segments)]
        near = int(np.argmin(np.hypot(poses[:, 0] - pose[0], poses[:, 1] - pose[1])))
        step = np.hypot(*np.diff(poses[:, :2], axis=0).T)
        ahead = near + int(np.searchsorted(np.cumsum(step[near:]), BLOCK_LOOKAHEAD)) + 1
        checker = self._unmapped_checker()
        return checker is not None and not bool(checker.free(poses[near:ahead + 1]).all())

    def _fail(self, message: str) -> Command:
        self.status, self.message = "failed", message
        self._failed = True
        return STOP
