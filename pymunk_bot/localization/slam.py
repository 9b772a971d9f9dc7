"""Pose-graph SLAM: the robot maps as it goes and corrects its odometry against its own map.

- **Front end.** Every ``keyframe_d`` of travel or ``keyframe_a`` of turn (by odometry), the
  new scan is aligned by point-to-line ICP (icp.py) with line fits of the end points of the
  latest ``LOCAL_KEYFRAMES`` keyframes (each fit weighed by how thin a line it is: a chain of
  matches adds up what corners taken for lines turn each one by; each fit of one face of a
  surface, the side it was seen from, and a point paired only with a face towards the LiDAR:
  a thin wall seen from both rooms had both faces in one fit), from the odometry
  prediction, with the odometry as the match's prior (odometry_trust.py: an uncalibrated
  robot's step error, fitted to what the matches show of this robot's odometry); its heading
  is then taken again against the latest ``HEADING_KEYFRAMES``, its position held
  (``_heading_over_longer_submap``). (Matching against the occupancy grid itself was
  tried: its 5 cm cells bias each match by millimetres and milliradians, and those add up
  over hundreds of keyframes.) The matched pose becomes a keyframe, joined to the previous
  one by an edge with the match's covariance, and its scan is folded into the map
  (mapping.py); a match with few points on the submap (a turn towards what it has not seen)
  counts when the prior explains it (``front_end_accepts``), else the keyframe takes the
  prediction.
- **Loop closures.** Candidates come from the graph's uncertainty (loopsearch.py): the
  keyframes passed at least ``loop_min_travel`` of driving ago that the newest keyframe could
  be within ``loop_radius`` of, at LOOP_GATE standard deviations of the chain's accumulated
  covariance between them. The nearest is verified by aligning the new scan (ICP) with that
  old keyframe's submap (it and SUBMAP_NEIGHBOURS either side): a closure needs
  ``loop_min_inliers`` of its points on the submap, a well-constrained match, a correction the
  accumulated covariance explains, and no other pose along the match's worst axis that fits
  as well (loopverify.py). A verified closure is a robust edge
  (Cauchy's kernel of scale ``loop_kernel``, posegraph.py): a wrong one the rest of the graph
  contradicts weighs next to nothing. ``closures`` records each accepted one,
  ``closures_rejected`` counts candidates that failed verification.
- **Walls** (``wall_landmarks``, on by default, walls.py). Each keyframe's long straight walls
  (unbroken by gaps) are observations of wall landmarks (a segment seen overlapping, not any
  parallel wall); each is
  a factor between the keyframe's heading and the landmark's direction in the graph, so every
  keyframe that sees a wall refines its direction and holds the others' headings to it.
- **Back end.** After a loop closure the graph is optimized (posegraph.py, sparse Gauss-Newton),
  the wall landmarks with it, and the map is rebuilt from every keyframe's scan at its
  optimized pose, when it is next read. (Optimizing every 10 keyframes for the walls as well
  moved the front end's submap under it: warehouse, uncalibrated, 14 of 20 runs within 5 cm
  against 15 without; docs/localization-journal.md.)
The estimate starts at the true start pose, so the map and the pose live in the world frame.
Between keyframes the pose is the last keyframe's composed with the odometry since.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.config.localization import MappingConfig, SlamConfig
from pymunk_bot.localization.loopsearch import ChainUncertainty, candidates
from pymunk_bot.localization.loopverify import LOOP_GATE, verify_closure
from pymunk_bot.localization.mapping import OccupancyMapper
from pymunk_bot.localization.moving import MovingReturns
from pymunk_bot.localization.odometry_trust import OdometryTrust
from pymunk_bot.localization.posegraph import Edge, edge_information, final_weights, optimize
from pymunk_bot.localization.icp import Reference, icp, seen_from
from pymunk_bot.localization.scanmatch import Match, subsample
from pymunk_bot.localization.se2 import between, compose, scan_points, transform_points, wrap
from pymunk_bot.localization.walls import WallLandmarks, long_walls

# [m^2, m^2, rad^2] added to every edge covariance. The heading's is 0.06 deg: the matches'
# own heading std (0.05-0.6 deg a step; their step heading errors as large, instrumented
# with bench.slam_heading_probe) is honest, and a floor of 0.3 deg let a loop closure bend
# ~180 keyframes' headings a little each instead of moving them (warehouse, uncalibrated,
# seed 3: the middle of the loop 10-15 cm off after its one closure, ATE 7.2 cm; 4.1 cm).
# The position's is 3 mm: the matches' own position std (2.6-6.5 mm a step, median) is
# honest too (chain edges' real errors 1.7-6.2 mm RMS, warehouse), and a floor of 1 cm made
# every chain edge as loose across an aisle as along it (docs/localization-journal.md).
EDGE_FLOOR = np.diag([0.003, 0.003, 0.001]) ** 2
LOCAL_KEYFRAMES = 10  # the front end matches against this many latest keyframes
HEADING_KEYFRAMES = 50  # ... and takes its heading again against this many (10 m at keyframe_d)
SUBMAP_NEIGHBOURS = 10  # keyframes either side of a loop candidate in its submap
MIN_KEYFRAMES_BETWEEN_CLOSURES = 10
KEYFRAMES_BETWEEN_ATTEMPTS = 2  # a failed verification waits this long (bounds the cost)
HEADING_RETRY = math.radians(3.0)  # [rad] between the headings a failed front-end match retries
MAX_HEADING_RETRY = math.radians(12.0)  # [rad] ... out to this far either way (bounds the cost)
MAX_SEARCH_STD = 0.5  # [m] the uncertainty counted at most (the ICP cannot reach farther)
OVERRULED_WEIGHT = 0.1  # a closure whose kernel weight falls below this is overruled
# A keyframe keeps at least this share of its returns: past it, the prediction is too far off
# for the free-space test (walls land in free space) and only the moving test counts.
MIN_STATIC_SHARE = 0.4
MATCH_INLIERS = 0.5  # a front-end match with more than this share of its points on the submap
# is taken as it is; one with fewer (a robot turning to face what the submap has not seen)
# when the odometry's prior explains its correction at chi^2_3 (99 %): PRIOR_CONSISTENCY.
PRIOR_CONSISTENCY = 11.34


@dataclass(frozen=True)
class FrontEndStep:
    """The front end's latest keyframe match, for instruments (bench/slam_heading_probe.py):
    the odometry's prediction from the previous keyframe and the prior it held the match to."""

    last: np.ndarray  # [x, y, theta] the previous keyframe's pose when the match was made
    predicted: np.ndarray  # [x, y, theta] the odometry's prediction (the match's prior mean)
    prior: np.ndarray  # 3x3 information of the prediction (world frame)
    pose: np.ndarray  # [x, y, theta] the keyframe's pose: the match's, or the prediction's
    covariance: np.ndarray  # 3x3 of ``pose`` (world frame)
    matched: bool  # False: the match failed and the keyframe took the prediction


@dataclass(frozen=True)
class LoopClosure:
    """An accepted loop closure: keyframe ``new`` seen from keyframe ``old`` at ``relative``."""

    old: int
    new: int
    relative: np.ndarray  # [x, y, theta] of new in old's frame, as the scan match measured it
    correction: float  # [m] how far the match moved the new keyframe from its estimate


def front_end_accepts(match: Match, predicted: np.ndarray, prior: np.ndarray) -> bool:
    """Whether a front-end ``match`` is kept: a well-conditioned fit with more than
    MATCH_INLIERS of its points on the submap, or with fewer but a correction from the
    odometry's prediction ``predicted`` [x, y, theta] that the prediction's uncertainty (the
    inverse of ``prior``, its information) and the match's explain. Rejected, the keyframe took
    the prediction instead: a few degrees off after a turn (an uncalibrated robot's odometry),
    and every later match against that keyframe's scan inherited them (the Nav2 depot,
    uncalibrated, seed 5: ATE 60 cm; docs/localization-journal.md)."""
    if not match.ok:
        return False
    if match.inliers > MATCH_INLIERS:
        return True
    correction = np.asarray(match.pose, dtype=float) - np.asarray(predicted, dtype=float)
    correction[2] = float(wrap(correction[2]))
    spread = np.linalg.inv(prior) + match.covariance
    return float(correction @ np.linalg.solve(spread, correction)) <= PRIOR_CONSISTENCY


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
        self._sensor = np.asarray(context.lidar_offset[:2], dtype=float)  # [m] robot frame
        self.keyframe_times: list[float] = []  # [s] when each keyframe's scan was taken
        self._scans: list = []  # the LaserScan of each keyframe
        self._points: list[np.ndarray] = []  # its subsampled end points, robot frame
        self._odom: list[np.ndarray] = []  # odometry at each keyframe
        self._local: list[np.ndarray] = []  # all end points of each keyframe's scan, robot frame
        self._travel: list[float] = []  # odometry distance driven up to each keyframe [m]
        self.edges: list[Edge] = []
        self.loop_closures: list[tuple[int, int]] = []  # (old, new) of each accepted closure
        self.closures: list[LoopClosure] = []
        self.closures_rejected = 0  # candidates whose verification failed
        self.keyframe_limit_reached = False  # past max_keyframes the estimate is odometry only
        self._last_closure = -MIN_KEYFRAMES_BETWEEN_CLOSURES
        self._last_attempt = -KEYFRAMES_BETWEEN_ATTEMPTS
        self._map_stale = False  # the graph moved since the map was built
        self.uncertainty = ChainUncertainty()
        self.odometry_trust = OdometryTrust()  # the front end's odometry prior, learned
        # recent scans, to find returns of things that move (moving.py)
        self._moving = MovingReturns(config.moving_window, config.moving_margin, config.moving_blob)
        # the front end's submap: the latest keyframes' scans, for the seen-free test
        self._submap_scans = MovingReturns(math.inf, config.moving_margin, config.moving_blob,
                                           scans=LOCAL_KEYFRAMES, spacing=0.0)
        self.returns_left_out = 0  # returns of keyframes left out as moving or seen free, in all
        self.front_end_step: FrontEndStep | None = None  # the latest keyframe's match
        self.walls = WallLandmarks()  # long straight walls seen, as graph landmarks

    @property
    def grid(self) -> OccupancyGrid:
        """The occupancy grid built from the keyframes at their (optimized) poses (rebuilt
        from every keyframe's scan if the graph moved since it was built)."""
        if self._map_stale:
            self.mapper.reset()
            for pose, scan in zip(self.keyframes, self._scans):
                self.mapper.integrate(pose, scan)
            self._map_stale = False
        return self.mapper.grid

    def closures_overruled(self) -> int:
        """Accepted closures the optimized graph has all but switched off (kernel weight below
        OVERRULED_WEIGHT): the rest of the graph contradicts them."""
        loops = [e for e in self.edges if e.robust > 0.0]
        return int(np.count_nonzero(final_weights(np.asarray(self.keyframes), loops) < OVERRULED_WEIGHT))

    def due(self, time: float) -> bool:
        """Never: when SLAM stands as the robot's mapper (``localization: slam`` without a
        ``mapping`` key), its map is built from its own keyframes at their *estimated* poses,
        so the simulation must not fold scans in at the true pose as it does for ``mapping``."""
        return False

    def debug(self) -> dict[str, Any]:
        return {"keyframes": np.array(self.keyframes).reshape(-1, 3),
                "loop_closures": list(self.loop_closures),
                "closures_rejected": self.closures_rejected,
                "returns_left_out": self.returns_left_out,
                "keyframe_limit_reached": self.keyframe_limit_reached}

    # ------------------------------------------------------------------ update
    def update(self, inputs: LocalizerInputs) -> None:
        odom = np.asarray(inputs.odometry, dtype=float)
        scan = inputs.scan
        fresh = scan is not None and abs(scan.time - inputs.time) < 1e-9
        self._update(odom, scan, fresh, inputs.time)
        if fresh and self.config.reject_moving:
            self._moving.observe(scan, self.pose)

    def _update(self, odom: np.ndarray, scan, fresh: bool, time: float) -> None:
        if not self.keyframes:
            if fresh:
                self._add_keyframe(np.asarray(self.context.start_pose, dtype=float), odom, scan,
                                   0.0, None, time)
            return
        moved = between(self._odom[-1], odom)
        predicted, prior = self.odometry_trust.predict(self.keyframes[-1], moved)
        self.pose = predicted
        if self.keyframe_limit_reached:  # the graph is full: dead reckoning from here on
            return
        if fresh and (np.hypot(moved[0], moved[1]) >= self.config.keyframe_d
                      or abs(moved[2]) >= self.config.keyframe_a):
            travel = self._travel[-1] + float(np.hypot(moved[0], moved[1]))
            static = self.static_returns(scan, predicted)
            points = subsample(scan_points(scan)[0][static], self.config.max_beams)
            match = self._heading_over_longer_submap(
                self._front_end_match(points, predicted, prior), points)
            matched = front_end_accepts(match, predicted, prior)
            if matched:
                pose, cov = match.pose, match.covariance
                self.odometry_trust.learn(moved, predicted, pose, cov, prior)
            else:
                pose, cov = predicted, np.diag([0.05, 0.05, 0.05]) ** 2
            self.front_end_step = FrontEndStep(self.keyframes[-1].copy(), predicted, prior,
                                               np.array(pose, dtype=float), cov, matched)
            self._add_keyframe(pose, odom, scan, travel, cov, time, static)
            self.pose = pose
            self.covariance = cov

    def static_returns(self, scan, predicted: np.ndarray) -> np.ndarray:
        """Boolean per return of ``scan`` (``scan_points`` order) taken at the predicted pose
        ``predicted`` [x, y, theta]: which are kept as the static world. Left out, both tests
        moving.py's (a return where an earlier beam reached more than ``moving_margin`` beyond
        it, and the rest of its blob), each earlier scan placed where this SLAM put it (its
        keyframe and the odometry since: a second of raw odometry, a few degrees off in a
        cluttered room, made walls look moving):

        - *moving* (``reject_moving``): it entered space one of the last ``moving_window``
          seconds of scans saw free (a walker crossing or coming closer);
        - *seen free* (``reject_free``): it lies in space one of the front end's submap
          keyframes (the latest LOCAL_KEYFRAMES) saw free (a walker where the robot saw the
          floor a few seconds ago, one walking away from it too). The submap's, not the whole
          map's: an old pass's walls, a degree or two off where no loop has closed yet, made
          the far walls look like they stood in free space.

        Neither where this map holds a surface hit by more than one keyframe within
        ``surface_radius`` (a thin pole one scan's beams straddled, an edge seen anew). A test
        that would leave fewer than MIN_STATIC_SHARE of the returns is not applied: then the
        prediction, not the world, is off."""
        c = self.config
        points, _ = scan_points(scan)
        static = np.ones(points.shape[0], dtype=bool)
        if not points.shape[0] or not (c.reject_moving or c.reject_free):
            return static
        # The map as it stands: after a loop closure its older keyframes sit where they were
        # before the graph moved them (a few cm), which this test tolerates; rebuilding it
        # from every keyframe after each closure made a 22-lap tour several times slower.
        held = self.mapper.near_surface(transform_points(predicted, points), c.surface_radius,
                                        self.mapper.config.hit_probability)
        for on, scans in ((c.reject_moving, self._moving), (c.reject_free, self._submap_scans)):
            if on:
                flagged = scans.flag(scan, predicted) & ~held
                if np.count_nonzero(static & ~flagged) >= MIN_STATIC_SHARE * points.shape[0]:
                    static &= ~flagged
        return static

    def _front_end_match(self, points: np.ndarray, predicted: np.ndarray, prior: np.ndarray) -> Match:
        """The new scan aligned with the latest keyframes' submap, from the odometry's
        prediction. An uncalibrated robot's odometry can be several degrees off over one step;
        at 5 m a few degrees put every point beyond ``max_pair`` of its surface and the match
        fails. Then it is tried again from headings HEADING_RETRY apart, out to
        MAX_HEADING_RETRY either way, and the match with the most inliers wins (the prior stays
        at the prediction: centred on each retry's start, it pulled the match that way). Out to
        that bound, not to a few standard deviations of the prior's heading: the prior's model
        is a robot's typical step, and an uncalibrated robot driving at 1 m/s has tails beyond
        it (warehouse, uncalibrated, revisiting, seed 2: the body turned 20.6 deg in 1 s, its
        odometry 0.3 deg the other way, the wheels' scale errors and noise 2.6 std off; one
        0.4 s step 12 deg off, beyond the 10 deg that 3 std reached, and the keyframe that took
        the prediction turned every later match 25 deg)."""
        c = self.config
        reference = self._reference(range(max(0, len(self.keyframes) - LOCAL_KEYFRAMES),
                                          len(self.keyframes)))
        match = icp(reference, points, predicted, c.iterations, c.max_pair, c.huber, prior=prior,
                    sensor=self._sensor)
        if match.ok and match.inliers > MATCH_INLIERS:
            return match
        for k in range(1, int(round(MAX_HEADING_RETRY / HEADING_RETRY)) + 1):
            for sign in (1.0, -1.0):
                guess = predicted + np.array([0.0, 0.0, sign * k * HEADING_RETRY])
                retry = icp(reference, points, predicted, c.iterations, c.max_pair, c.huber,
                            prior=prior, start=guess, sensor=self._sensor)
                if retry.ok and (not match.ok or retry.inliers > match.inliers):
                    match = retry
        return match

    def _heading_over_longer_submap(self, match: Match, points: np.ndarray) -> Match:
        """``match`` with its heading taken again against the latest HEADING_KEYFRAMES
        keyframes, its position held where it was by the position information the match
        stated. The heading is what a chain of matches random-walks in: a short, sparse or
        noisy LiDAR's match is 0.1-0.2 deg off a keyframe against LOCAL_KEYFRAMES of submap,
        and walls seen over the last 10 m of driving hold the direction that 2 m cannot. The
        position stays the short submap's: over a longer one an uncalibrated robot's travel
        error (a few cm) puts older keyframes' surfaces off along an aisle. The match keeps
        its stated covariance: the longer match's, tighter in heading, made the offices' one-way
        median ATE 1.73 cm against 1.45 (replayed; docs/localization-journal.md, "SLAM: a
        heading held over 10 m, and closures that are unique")."""
        count = len(self.keyframes)
        if not match.ok or count <= LOCAL_KEYFRAMES:
            return match
        held = np.zeros((3, 3))
        held[:2, :2] = np.linalg.inv(match.covariance)[:2, :2]  # position only: heading free
        c = self.config
        longer = icp(self._reference(range(max(0, count - HEADING_KEYFRAMES), count)), points,
                     match.pose, c.iterations, c.max_pair, c.huber, prior=held, sensor=self._sensor)
        if not longer.ok:
            return match
        return replace(match, pose=longer.pose)

    def _add_keyframe(self, pose, odom, scan, travel, cov, time: float,
                      static: np.ndarray | None = None) -> None:
        """A keyframe at ``pose`` of ``scan``; ``static``: which returns its submaps keep
        (all when None)."""
        index = len(self.keyframes)
        self.keyframes.append(np.array(pose, dtype=float))
        self.keyframe_times.append(float(time))
        self._scans.append(scan)
        points, _ = scan_points(scan)
        if static is not None:
            self.returns_left_out += int(np.count_nonzero(~static))
            points = points[static]
        self._points.append(subsample(points, self.config.max_beams))
        self._local.append(points)
        self._odom.append(odom.copy())
        self._travel.append(travel)
        if cov is not None:
            z = between(self.keyframes[index - 1], self.keyframes[index])
            self.edges.append(Edge(index - 1, index, z,
                                   edge_information(cov + EDGE_FLOOR, float(self.keyframes[index][2]))))
        self.uncertainty.add(self.keyframes[index], np.zeros((3, 3)) if cov is None else cov + EDGE_FLOOR)
        # Integrated even when the graph has moved since the map was built (the next read
        # rebuilds it from every keyframe): static_returns asks it for surfaces as it stands.
        self.mapper.integrate(self.keyframes[index], scan)
        self._submap_scans.observe(scan, self.keyframes[index])
        self._close_loop(index)
        if self.config.wall_landmarks:  # in the graph from the next optimization on
            self.walls.observe(index, self.keyframes, long_walls(self._local[index]))
        self.keyframe_limit_reached = len(self.keyframes) >= self.config.max_keyframes

    def _reference(self, keyframes, weighed: bool = True) -> Reference:
        """The surfaces (line fits) of these keyframes' end points, in the world frame, each
        of the face its keyframes saw (icp.Reference.surfaces' ``facing``); ``weighed``: each
        fit weighed by how thin a line it is."""
        points, facing = zip(*(seen_from(self.keyframes[k], self._local[k], self._sensor)
                               for k in keyframes))
        return Reference.surfaces(np.concatenate(points), weighed=weighed, facing=np.concatenate(facing))

    # ------------------------------------------------------------------ loops
    def _close_loop(self, index: int) -> bool:
        """Look for a loop closure of keyframe ``index`` (module docstring); True if one was
        accepted."""
        c = self.config
        if (index - self._last_closure < MIN_KEYFRAMES_BETWEEN_CLOSURES
                or index - self._last_attempt < KEYFRAMES_BETWEEN_ATTEMPTS):
            return False
        position_cov, heading_var = self.uncertainty.relative(index)
        found = candidates(np.asarray(self.keyframes), np.asarray(self._travel), position_cov,
                           c.loop_radius, c.loop_min_travel, LOOP_GATE, MAX_SEARCH_STD)
        if found.size == 0:
            return False
        self._last_attempt = index
        old = int(found[0])
        accumulated = np.zeros((3, 3))
        accumulated[:2, :2], accumulated[2, 2] = position_cov[old], heading_var[old]
        match = self._loop_match(old, index, accumulated)
        if match is None:
            self.closures_rejected += 1
            return False
        self.add_closure(old, index, between(self.keyframes[old], match.pose), match.covariance)
        return True

    def add_closure(self, old: int, new: int, relative: np.ndarray, covariance: np.ndarray) -> None:
        """Join keyframes ``old`` and ``new`` by a loop edge (robust: Cauchy's kernel of scale
        ``loop_kernel``): ``new`` seen from ``old`` at ``relative`` [x, y, theta], with
        ``covariance`` (3x3, world frame: a scan match's of ``new``'s pose); the graph is
        optimized every ``optimize_every`` closures."""
        relative = np.asarray(relative, dtype=float)
        seen = compose(self.keyframes[old], relative)
        self.edges.append(Edge(old, new, relative,
                               edge_information(np.asarray(covariance) + EDGE_FLOOR, float(seen[2])),
                               robust=self.config.loop_kernel))
        self.loop_closures.append((old, new))
        self.closures.append(LoopClosure(old, new, relative,
                                         float(np.hypot(*(seen[:2] - self.keyframes[new][:2])))))
        self._last_closure = new
        if len(self.loop_closures) % self.config.optimize_every == 0:
            self._optimize()

    def _loop_match(self, old: int, index: int, accumulated: np.ndarray) -> Match | None:
        """The scan of keyframe ``index`` aligned with the submap around keyframe ``old`` (it
        and SUBMAP_NEIGHBOURS either side), if the match verifies a closure (loopverify.py):
        ``accumulated`` is the 3x3 covariance of ``index`` relative to ``old``."""
        c = self.config
        lo, hi = max(0, old - SUBMAP_NEIGHBOURS), min(index, old + SUBMAP_NEIGHBOURS + 1)
        return verify_closure(self._reference(range(lo, hi), weighed=False), self._points[index],
                              self.keyframes[index], accumulated, EDGE_FLOOR,
                              iterations=c.iterations, max_pair=c.max_pair, huber=c.huber,
                              min_inliers=c.loop_min_inliers, sensor=self._sensor)

    def _optimize(self) -> None:
        walls = self.walls.factors(self.keyframes) if self.config.wall_landmarks else None
        poses, _ = optimize(np.asarray(self.keyframes), self.edges, walls=walls)
        self.keyframes = [p for p in poses]
        self.uncertainty.move(poses)
        self._map_stale = True
        self._moving.forget()  # the recent scans were placed where the graph no longer is
        self._submap_scans.forget()
        for pose, scan in list(zip(self.keyframes, self._scans))[-LOCAL_KEYFRAMES:]:
            self._submap_scans.observe(scan, pose)
