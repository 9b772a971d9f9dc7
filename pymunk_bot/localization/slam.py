"""Pose-graph SLAM: the robot maps as it goes and corrects its odometry against its own map.

- **Front end.** Every ``keyframe_d`` of travel or ``keyframe_a`` of turn (by odometry), the
  new scan is aligned by point-to-line ICP (icp.py) with line fits of the end points of the
  latest ``LOCAL_KEYFRAMES`` keyframes, from the odometry prediction, with the odometry as the
  match's prior (odometry_trust.py: an uncalibrated robot's step error, fitted to what the
  matches show of this robot's odometry). (Matching against the occupancy grid itself was
  tried: its 5 cm cells bias each match by millimetres and milliradians, and those add up
  over hundreds of keyframes.) The matched pose becomes a
  keyframe, joined to the previous one by an edge with the match's covariance, and its scan
  is folded into the map (mapping.py).
- **Loop closures.** A keyframe within ``loop_radius`` of one passed at least
  ``loop_min_travel`` metres of driving earlier is aligned (ICP) with that old keyframe and
  its neighbours; a match with at least ``loop_min_inliers`` of its points on them adds a
  loop edge.
- **Back end.** After a loop closure the graph is optimized (posegraph.py, sparse Gauss-Newton)
  and the map is rebuilt from every keyframe's scan at its optimized pose.
The estimate starts at the true start pose, so the map and the pose live in the world frame.
Between keyframes the pose is the last keyframe's composed with the odometry since.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.localization.config import MappingConfig, SlamConfig
from pymunk_bot.localization.mapping import OccupancyMapper
from pymunk_bot.localization.odometry_trust import OdometryTrust
from pymunk_bot.localization.posegraph import Edge, optimize
from pymunk_bot.localization.icp import Reference, icp
from pymunk_bot.localization.scanmatch import subsample
from pymunk_bot.localization.se2 import between, scan_points, transform_points

EDGE_FLOOR = np.diag([0.01, 0.01, 0.005]) ** 2  # [m^2, m^2, rad^2] added to every edge covariance
LOCAL_KEYFRAMES = 10  # the front end matches against this many latest keyframes
SUBMAP_NEIGHBOURS = 10  # keyframes either side of a loop candidate in its submap
MIN_KEYFRAMES_BETWEEN_CLOSURES = 10


class SlamLocalizer(Localizer):
    """Graph SLAM from odometry and LiDAR; ``grid`` is the map it has built."""

    needs_map = False
    needs_lidar = True

    def __init__(self, config: SlamConfig, context: LocalizerContext) -> None:
        super().__init__(config, context)
        self.mapper = OccupancyMapper.for_arena(
            MappingConfig(resolution=config.resolution, margin=config.margin), context.arena,
            context.origin)
        self.covariance = np.zeros((3, 3))
        self.keyframes: list[np.ndarray] = []  # estimated poses
        self._scans: list = []  # the LaserScan of each keyframe
        self._points: list[np.ndarray] = []  # its subsampled end points, robot frame
        self._odom: list[np.ndarray] = []  # odometry at each keyframe
        self._local: list[np.ndarray] = []  # all end points of each keyframe's scan, robot frame
        self._travel: list[float] = []  # odometry distance driven up to each keyframe [m]
        self.edges: list[Edge] = []
        self.loop_closures: list[tuple[int, int]] = []
        self.keyframe_limit_reached = False  # past max_keyframes the estimate is odometry only
        self._last_closure = -MIN_KEYFRAMES_BETWEEN_CLOSURES
        self.odometry_trust = OdometryTrust()  # the front end's odometry prior, learned

    @property
    def grid(self) -> OccupancyGrid:
        """The occupancy grid built from the keyframes at their (optimized) poses."""
        return self.mapper.grid

    def due(self, time: float) -> bool:
        """Never: when SLAM stands as the robot's mapper (``localization: slam`` without a
        ``mapping`` key), its map is built from its own keyframes at their *estimated* poses,
        so the simulation must not fold scans in at the true pose as it does for ``mapping``."""
        return False

    def debug(self) -> dict[str, Any]:
        return {"keyframes": np.array(self.keyframes).reshape(-1, 3),
                "loop_closures": list(self.loop_closures),
                "keyframe_limit_reached": self.keyframe_limit_reached}

    # ------------------------------------------------------------------ update
    def update(self, inputs: LocalizerInputs) -> None:
        odom = np.asarray(inputs.odometry, dtype=float)
        scan = inputs.scan
        fresh = scan is not None and abs(scan.time - inputs.time) < 1e-9
        if not self.keyframes:
            if fresh:
                self._add_keyframe(np.asarray(self.context.start_pose, dtype=float), odom, scan,
                                   0.0, None)
            return
        moved = between(self._odom[-1], odom)
        predicted, prior = self.odometry_trust.predict(self.keyframes[-1], moved)
        self.pose = predicted
        if self.keyframe_limit_reached:  # the graph is full: dead reckoning from here on
            return
        if fresh and (np.hypot(moved[0], moved[1]) >= self.config.keyframe_d
                      or abs(moved[2]) >= self.config.keyframe_a):
            travel = self._travel[-1] + float(np.hypot(moved[0], moved[1]))
            points = subsample(scan_points(scan)[0], self.config.max_beams)
            c = self.config
            match = icp(self._reference(range(max(0, len(self.keyframes) - LOCAL_KEYFRAMES),
                                              len(self.keyframes))), points, predicted,
                        c.iterations, c.max_pair, c.huber, prior=prior)
            if match.ok and match.inliers > 0.5:
                pose, cov = match.pose, match.covariance
                self.odometry_trust.learn(moved, predicted, pose, cov, prior)
            else:
                pose, cov = predicted, np.diag([0.05, 0.05, 0.05]) ** 2
            self._add_keyframe(pose, odom, scan, travel, cov)
            self.pose = pose
            self.covariance = cov

    def _add_keyframe(self, pose, odom, scan, travel, cov) -> None:
        index = len(self.keyframes)
        self.keyframes.append(np.array(pose, dtype=float))
        self._scans.append(scan)
        points, _ = scan_points(scan)
        self._points.append(subsample(points, self.config.max_beams))
        self._local.append(points)
        self._odom.append(odom.copy())
        self._travel.append(travel)
        if cov is not None:
            z = between(self.keyframes[index - 1], self.keyframes[index])
            self.edges.append(Edge(index - 1, index, z, np.linalg.inv(cov + EDGE_FLOOR)))
        self.mapper.integrate(self.keyframes[index], scan)
        self._close_loop(index)
        self.keyframe_limit_reached = len(self.keyframes) >= self.config.max_keyframes

    def _reference(self, keyframes) -> Reference:
        """The surfaces (line fits) of these keyframes' end points, in the world frame."""
        return Reference.surfaces(np.concatenate([transform_points(self.keyframes[k], self._local[k])
                                                  for k in keyframes]))

    # ------------------------------------------------------------------ loops
    def _close_loop(self, index: int) -> bool:
        c = self.config
        if index - self._last_closure < MIN_KEYFRAMES_BETWEEN_CLOSURES:
            return False
        here = self.keyframes[index]
        travel = np.asarray(self._travel)
        poses = np.asarray(self.keyframes)
        far_back = np.flatnonzero(travel[index] - travel >= c.loop_min_travel)
        if far_back.size == 0:
            return False
        dist = np.hypot(*(poses[far_back, :2] - here[:2]).T)
        if dist.min() > c.loop_radius:
            return False
        old = int(far_back[np.argmin(dist)])
        lo, hi = max(0, old - SUBMAP_NEIGHBOURS), min(index, old + SUBMAP_NEIGHBOURS + 1)
        match = icp(self._reference(range(lo, hi)), self._points[index], here, c.iterations,
                    c.max_pair, c.huber)
        if not (match.ok and match.inliers >= c.loop_min_inliers):
            return False
        z = between(self.keyframes[old], match.pose)
        self.edges.append(Edge(old, index, z, np.linalg.inv(match.covariance + EDGE_FLOOR)))
        self.loop_closures.append((old, index))
        self._last_closure = index
        if len(self.loop_closures) % c.optimize_every == 0:
            self._optimize()
        return True

    def _optimize(self) -> None:
        poses, _ = optimize(np.asarray(self.keyframes), self.edges)
        self.keyframes = [p for p in poses]
        self.mapper.reset()
        for pose, scan in zip(self.keyframes, self._scans):
            self.mapper.integrate(pose, scan)
