"""``navigate`` for a car-like robot: Hybrid A* on the map, then pure pursuit segment by segment.

The planner (:mod:`pymunk_bot.planning.hybrid_astar`) finds a path the car can drive, with its
real footprint checked along every arc, that may back up. The path is cut where the direction
changes; each segment is followed with pure pursuit (in reverse, with the rear as the front),
braking to a stop at its end before the next begins. Off the path or without progress for
``stuck_time`` it replans from where it is. With a LiDAR, the scan's returns that the map does
not explain are added to the map of the next plan, and a return right ahead stops the car.
"""
from __future__ import annotations

import math

import numpy as np

from ..config.controllers import NavigateControllerConfig
from ..footprint import Footprint
from ..geometry import wrap_angle
from ..planning.dwa import scan_points
from ..planning.grid import ClearanceGrid
from ..planning.hybrid_astar import FootprintChecker, HybridParams, HybridResult, hybrid_astar
from ..planning.map import MapInfo
from ..planning.pursuit import PathTracker, PursuitGains
from ..planning.steering import car_pursue
from .base import STOP, Command, Controller, Observation, RobotSpec

OFF_PATH = 0.5  # [m] farther than this from the segment: replan
SEGMENT_END = 0.08  # [m] a segment is done this close to its end
STOP_DISTANCE = 0.25  # [m] a scan return this close ahead of the footprint stops the car
MIN_LOOKAHEAD = 0.3  # [m]


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
        if self._failed:
            return STOP
        tolerance = self.config.tolerance if self.config.tolerance is not None else obs.goal_tolerance
        pose = np.asarray(obs.pose, dtype=float)
        if self._arrived(pose, goal, tolerance) and (not self.segments or len(self.segments) == 1
                                                     and self.segments[0][1].remaining() < 0.1):
            self.status, self.message = "arrived", ""
            return STOP
        if not self.segments and not self._plan(pose, goal, tolerance, obs.time):
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
        end = tracker.points[-1]
        if tracker.remaining() < SEGMENT_END or math.dist(end, (x, y)) < SEGMENT_END:
            self.segments.pop(0)
            self._progress = (0.0, obs.time)
            if not self.segments:
                return STOP
            return STOP  # stop for a tick before driving the other way
        if obs.scan is not None and self._blocked(obs, direction):
            self.message = "stopped: something not on the map is in the way"
            return STOP
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
    def _plan(self, pose, goal, tolerance: float, now: float) -> bool:
        self.replans += 1
        if self.checker is None:
            return False
        smallest = float(self.discs[1].min())
        self.plan = hybrid_astar(self.checker, pose, goal, 0.5 * tolerance,
                                 self.robot.min_turn_radius, self.params, self.config.heading,
                                 self.config.heading_tolerance, heuristic_clearance=smallest)
        if not self.plan.found:
            self._fail(f"{self.plan.reason} (plan {self.replans})")
            return False
        self.segments = [(d, PathTracker([tuple(p) for p in poses[:, :2]], False, self.gains))
                         for d, poses in self.plan.segments() if len(poses) >= 2]
        self._segment_poses = [poses for _, poses in self.plan.segments() if len(poses) >= 2]
        self._progress = (0.0, now)
        self.message = (f"following a {len(self.segments)}-segment drivable path "
                        f"(plan {self.replans}, {self.plan.expansions} expansions)")
        return bool(self.segments)

    @property
    def _end_heading(self) -> float:
        poses = self._segment_poses[len(self._segment_poses) - len(self.segments)]
        return float(poses[-1, 2])

    def _blocked(self, obs: Observation, direction: int) -> bool:
        """A return the map does not explain right ahead (or behind, in reverse)."""
        if obs.scan is None:
            return False
        points = scan_points(obs.scan)
        if not len(points):
            return False
        x, y, theta = (float(v) for v in obs.pose[:3])
        c, s = math.cos(theta), math.sin(theta)
        wx, wy = x + c * points[:, 0] - s * points[:, 1], y + s * points[:, 0] + c * points[:, 1]
        g = self.grid
        cols = np.clip((wx / g.resolution).astype(int), 0, g.cols - 1)
        rows = np.clip((wy / g.resolution).astype(int), 0, g.rows - 1)
        points = points[g.clearance[rows, cols] > 2.0 * g.resolution]
        if not len(points):
            return False
        centres, radii = self.discs
        reach = radii.max() + STOP_DISTANCE
        lead = centres[np.argmax(direction * centres[:, 0])]
        ahead = points - lead
        near = np.hypot(ahead[:, 0], ahead[:, 1]) < reach
        return bool((near & (direction * ahead[:, 0] > 0)).any())

    def _fail(self, message: str) -> Command:
        self.status, self.message = "failed", message
        self._failed = True
        return STOP
