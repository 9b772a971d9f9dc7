"""Global planning on the scenario's map plus local following and avoidance.

1. Plan: A* on a clearance grid of the map (:mod:`pymunk_bot.planning`), inflated by the robot
   radius (hard) plus a margin (soft cost), then line-of-sight smoothing.
2. Follow: pure pursuit proposes a command; with a LiDAR the Dynamic Window Approach filters it
   (the nearest arc on which the robot can still stop before anything it sees).
3. Watch: scan returns the map does not explain are remembered (and forgotten once a beam
   passes through them), each scan once, placed with the pose estimate of its time. When
   they block the path ahead, or the robot makes no progress along the path for
   ``stuck_time``, it replans around them; a replan that leaves it blocked by what it sees
   (its LiDAR vetoes every arc the path asks for) backs it off into free space first
   (:class:`~pymunk_bot.controllers.escape.Escape`).
4. Fail clearly: no path on the map itself is a permanent failure at once; no path only because
   of unmapped obstacles is retried until ``give_up_after`` seconds have passed, and so is no
   progress along any path (:class:`~pymunk_bot.controllers.progress.ProgressWatch`: replans
   do not reset its clock).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from pymunk_bot.config.controllers import NavigateControllerConfig
from pymunk_bot.planning.astar import astar
from pymunk_bot.planning.dwa import DynamicWindow, scan_points
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.planning.paths import shortcut
from pymunk_bot.planning.tracking import MovingObstacleTracker, PassingSide
from pymunk_bot.controllers.avoid import dwa_params
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec
from pymunk_bot.controllers.escape import Escape, to_robot_frame
from pymunk_bot.controllers.progress import PROGRESS_STEP
from pymunk_bot.controllers.scan_pose import ScanPoses
from pymunk_bot.controllers.waypoints import PathFollower, pursuit_gains

LOOK_AHEAD_FOR_BLOCKS = 2.5  # [m] of path ahead checked against unmapped obstacles
OFF_PATH = 1.0  # [m] farther than this from the path: replan from here
RETRY_PERIOD = 1.0  # [s] between replans while unmapped obstacles block every route
PATH_CORNER_RADIUS = 0.25  # [m] fillets on planned paths (small: they cut toward obstacles)


class NavigateController(Controller):
    """Plans on the map, follows the plan, avoids and replans around what the map missed."""

    needs_map = True

    def __init__(self, config: NavigateControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config, robot)
        self.robot = robot
        self.gains = pursuit_gains(config.pursuit, robot, self.max_speed, config.lookahead)
        # The window searches (v, omega) arcs of a diff drive; an omni robot follows the path.
        self.window = None if robot.holonomic else DynamicWindow(
            robot, dwa_params(config.dwa, self.max_speed), 1.0 / config.rate)
        self.hard = robot.radius + config.hard_margin  # [m] closer cells are blocked
        self.soft = robot.radius + config.margin  # [m] paths keep this much where they can
        self.map: MapInfo | None = None
        self.static: ClearanceGrid | None = None
        self.path: list[tuple[float, float]] | None = None
        self.follower: PathFollower | None = None
        self.unmapped: dict[tuple[int, int], tuple[float, float]] = {}  # cell -> point [m]
        self.replans = 0
        self._goal: tuple[float, float] | None = None
        self._blocked_since: float | None = None  # first failed replan in a row [s]
        self._next_retry = 0.0
        self._permanent = False
        self._progress = (0.0, 0.0)  # (path progress [m], when [s]): replans when stale
        self.command = (0.0, 0.0)  # last (v, omega)
        self.tracker = MovingObstacleTracker()  # other robots, from successive scans
        self.passing = PassingSide()
        self.escape = Escape()  # out of stalls where the LiDAR vetoes every arc the path asks
        # A LiDAR slower than the controller hands it the same scan on several ticks: each is
        # remembered once, placed with the pose it was taken from (not the pose now, which a
        # turn on the spot moves by tens of degrees: walls copied around the robot).
        self.scan_poses = ScanPoses(self.rate)

    def set_map(self, world_map: MapInfo) -> None:
        self.map = world_map if self.config.map_movable else world_map.without_movable()
        cap = self.soft + 2.0 * self.config.resolution
        self.static = ClearanceGrid.from_map(self.map, self.config.resolution, cap)

    def debug_path(self):
        return self.path

    def _static_grid(self) -> ClearanceGrid:
        """The map's clearance grid (built by set_map)."""
        if self.static is None:
            raise RuntimeError("navigate: no map (the simulation did not call set_map)")
        return self.static

    # ------------------------------------------------------------------ the control step
    def compute(self, obs: Observation) -> Command:
        goal = obs.goal  # the controller's own goal, or the robot's (see Observation)
        if goal is None:
            return self._fail("no goal: set controller.goal or the robot's goal", permanent=True)
        if self.static is None:
            return self._fail("no map (the simulation did not call set_map)", permanent=True)
        hold = self.hold_until_localized(obs)  # localize before driving (Controller)
        if hold is not None:
            return hold
        goal = (float(goal[0]), float(goal[1]))
        if goal != self._goal:
            self._reset(goal)
        x, y = float(obs.pose[0]), float(obs.pose[1])
        tolerance = self.config.tolerance if self.config.tolerance is not None else obs.goal_tolerance
        if math.hypot(goal[0] - x, goal[1] - y) <= 0.5 * tolerance:
            self.status, self.message = "arrived", ""
            return self._stop()
        if self._permanent:
            return self._stop()
        scan = obs.scan
        points: np.ndarray | None = None
        if scan is not None:
            points = scan_points(scan)
        taken_from = self.scan_poses.new_scan_pose(obs)
        if taken_from is not None and points is not None:
            self._remember(taken_from, points, scan)
        if self.follower is None:
            if obs.time < self._next_retry or not self._plan(obs, goal, tolerance):
                return self._stop()
        elif self._needs_replan(obs):
            if not self._plan(obs, goal, tolerance):
                return self._stop()
        follower = self.follower
        if follower is None:  # a successful _plan always makes one
            raise RuntimeError("navigate: a plan succeeded without a path to follow")
        if self.gave_up(obs, follower.tracker.s):  # along any path: replans do not reset it
            return self._fail(f"{self.message} after {self.replans} plans", permanent=True)
        self.status = "running"
        if self.window is None:
            command, _ = follower.drive(obs.pose)
            return command
        v, omega, _ = follower.command(obs.pose)
        wanted = v  # [m/s] what the path asks for
        if scan is not None and points is not None:
            # Other robots move: predict them, and keep right when one comes at us head-on.
            velocities, oncoming = self.tracker.update(
                scan.time, obs.pose, points, float(self.command[0]),
                self.robot.radius + self.window.params.safety)
            escape = self.escape.target(obs.pose, obs.time, points,
                                        self.robot.radius + self.window.params.safety,
                                        to_robot_frame(obs.pose, follower.carrot(obs.pose)[0]))
            if escape is not None:  # pressed against something: back off into free space
                v, omega = self.window.choose(*self.command, points, escape, wanted, velocities)
            elif oncoming is not None:
                carrot, speed, _ = follower.carrot(obs.pose)
                ahead = to_robot_frame(obs.pose, carrot)
                target = self.passing.target(obs.time, oncoming, ahead, self.robot.radius)
                v, omega = self.window.choose(*self.command, points, target, speed, velocities)
            else:
                self.passing.target(obs.time, None, np.zeros(2), self.robot.radius)
                # The LiDAR vetoes arcs that would hit something the map did not show.
                v, omega = self.window.track(*self.command, points, v, omega, velocities)
            self.escape.note(obs.time, v, wanted)
        self.command = (v, omega)
        return Command(v, omega)

    # ------------------------------------------------------------------ planning
    def _reset(self, goal: tuple[float, float]) -> None:
        self._goal = goal
        self.path = self.follower = None
        self._blocked_since = None
        self._permanent = False
        self._next_retry = 0.0
        self.watch.restart()
        self.status, self.message = "running", ""

    def _plan(self, obs: Observation, goal, tolerance: float) -> bool:
        """Plan from the pose estimate; on failure set status and the retry time."""
        self.replans += 1
        static = self._static_grid()
        grid = static
        if self.unmapped:
            grid = static.copy()
            grid.add_points(np.array(list(self.unmapped.values())))
        start = (float(obs.pose[0]), float(obs.pose[1]))
        result = astar(grid, start, goal, self.hard, self.soft, self.config.clearance_cost,
                       goal_radius=0.5 * tolerance)
        if result.path is not None:  # result.found
            self.path = shortcut(grid, result.path, self.soft)
            self.follower = PathFollower(self.path, False, self.gains, PATH_CORNER_RADIUS,
                                         1.0 / self.config.rate)
            self._progress = (0.0, obs.time)
            self.watch.rebase(0.0)  # progress along the new path counts; the clock runs on
            self._blocked_since = None
            self.message = f"following a {len(self.path)}-point path (plan {self.replans})"
            return True
        self.path = self.follower = None
        if grid is static:
            self._fail(f"{result.reason} on the map", permanent=True)
            return False
        # Maybe only the unmapped obstacles block it: does the map alone have a route?
        on_map = astar(static, start, goal, self.hard, self.soft,
                       self.config.clearance_cost, goal_radius=0.5 * tolerance)
        if not on_map.found:
            self._fail(f"{on_map.reason} on the map", permanent=True)
            return False
        if self._blocked_since is None:
            self._blocked_since = obs.time
        waited = obs.time - self._blocked_since
        if waited >= self.config.give_up_after:
            self._fail(f"no path: obstacles that are not on the map have blocked every route "
                       f"for {waited:.0f} s", permanent=True)
            return False
        self._next_retry = obs.time + RETRY_PERIOD
        self.status = "running"
        self.message = f"waiting: obstacles not on the map block every route ({waited:.0f} s)"
        return False

    def _needs_replan(self, obs: Observation) -> bool:
        if self.follower is None:
            raise RuntimeError("navigate: replanning checks need a path being followed")
        tracker = self.follower.tracker
        x, y = float(obs.pose[0]), float(obs.pose[1])
        near = tracker.point_at(tracker.s)
        if math.hypot(near[0] - x, near[1] - y) > OFF_PATH:
            return True
        if tracker.s > self._progress[0] + PROGRESS_STEP:
            self._progress = (tracker.s, obs.time)
        elif obs.time - self._progress[1] > self.config.stuck_time:
            return True
        if self.unmapped:
            ahead = tracker.points_at(np.arange(tracker.s, min(tracker.length, tracker.s
                                                               + LOOK_AHEAD_FOR_BLOCKS), 0.05))
            if len(ahead):
                pts = np.array(list(self.unmapped.values()))
                d2 = ((ahead[:, None, :] - pts[None, :, :]) ** 2).sum(axis=2)
                if float(d2.min()) < self.hard ** 2:
                    return True
        return False

    # ------------------------------------------------------------------ unmapped obstacles
    def _remember(self, pose, points: np.ndarray, scan) -> None:
        """Keep returns the map cannot explain; forget remembered ones a beam now passes."""
        x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
        c, s = math.cos(theta), math.sin(theta)
        res = self.config.resolution
        if len(points):
            world = np.column_stack([x + c * points[:, 0] - s * points[:, 1],
                                     y + s * points[:, 0] + c * points[:, 1]])
            grid = self._static_grid()
            rows, cols = grid.cells_of(world[:, 0], world[:, 1])
            inside = grid.inside(world[:, 0], world[:, 1])
            unexplained = inside & (grid.clearance[rows, cols] > 2.0 * res)
            for (px, py), r, k in zip(world[unexplained], rows[unexplained], cols[unexplained]):
                self.unmapped[(int(r), int(k))] = (float(px), float(py))
        if not self.unmapped:
            return
        keys = list(self.unmapped)
        pts = np.array([self.unmapped[k] for k in keys])
        ox = x + c * scan.offset[0] - s * scan.offset[1]
        oy = y + s * scan.offset[0] + c * scan.offset[1]
        dist = np.hypot(pts[:, 0] - ox, pts[:, 1] - oy)
        bearing = np.arctan2(pts[:, 1] - oy, pts[:, 0] - ox) - theta
        angles = np.asarray(scan.angles)
        ranges = np.asarray(scan.ranges)
        # a writeable copy: one array type for the kernel (a scan's may be read-only)
        beam, off = nearest_beams(bearing, np.array(angles, dtype=float))
        # Beam spacing from the beams themselves: a 90-degree LiDAR is not a full circle.
        step = float(np.median(np.abs(np.diff(angles)))) if len(angles) > 1 else np.inf
        covered = off <= step
        seen_through = covered & (ranges[beam] > dist + 2.0 * res)
        for key, gone in zip(keys, seen_through):
            if gone:
                del self.unmapped[key]

    # ------------------------------------------------------------------ helpers
    def _fail(self, message: str, permanent: bool) -> Command:
        self.status, self.message = "failed", message
        self._permanent = permanent
        return self._stop()

    def _stop(self) -> Command:
        self.command = (0.0, 0.0)
        return STOP


@numba.njit(cache=True, nogil=True)
def nearest_beams(bearing: np.ndarray, angles: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """For each bearing [rad], the beam whose angle is nearest around the circle (the first of
    equals) and the angle between them [rad]. Beams in increasing order over less than a turn
    (a LiDAR's) are searched by bisection, the few around the bearing compared; others all."""
    n = len(angles)
    turn = 2.0 * np.pi
    ordered = n > 1 and angles[n - 1] - angles[0] < turn
    for m in range(n - 1):
        ordered = ordered and angles[m + 1] > angles[m]
    beam = np.zeros(len(bearing), dtype=np.int64)
    off = np.full(len(bearing), np.inf)
    every = np.arange(n)
    near = np.empty(6, dtype=np.int64)
    for i in range(len(bearing)):
        candidates = every
        if ordered:  # the bracketing beams (and a spare each side), and both ends (the wrap)
            k = np.searchsorted(angles, angles[0] + (bearing[i] - angles[0]) % turn)
            near[0], near[1], near[2] = 0, max(k - 2, 0), max(k - 1, 0)
            near[3], near[4], near[5] = min(k, n - 1), min(k + 1, n - 1), n - 1
            candidates = near  # in increasing order: the first of equals wins
        for j in candidates:
            d = abs((bearing[i] - angles[j] + np.pi) % turn - np.pi)
            if d < off[i]:
                beam[i], off[i] = j, d
    return beam, off
