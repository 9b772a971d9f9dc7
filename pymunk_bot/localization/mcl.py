"""Monte Carlo localization as ROS AMCL does it, vectorised over particles with numpy.

Per update (after ``update_min_d`` of travel or ``update_min_a`` of turn, on a fresh scan):
1. move every particle by the odometry motion since the last update (motion.py);
2. weight it by the scan: AMCL's likelihood-field model (``p = 1 + sum pz^3`` with
   ``pz = z_hit exp(-d^2 / 2 sigma_hit^2) + z_rand / max_range``, d = distance from a beam's end
   to the nearest obstacle), its ``likelihood_field_prob`` (the product of pz while localized,
   tempered until then: see ``scan_likelihood``) or its beam model (expected ranges by sphere
   tracing); returns of things that moved (moving.py, no pose needed) and, while localized,
   returns short of the map (dynamic.py) are left out;
3. every ``resample_interval`` updates: low-variance resampling, KLD-sampling choosing how many
   particles (Fox 2003, AMCL's 0.5 m x 0.5 m x 10 deg histogram), and recovery: a fraction
   ``max(0, 1 - w_fast / w_slow)`` of the new particles is drawn uniformly over free space;
   then roughening (not AMCL's): a jitter in proportion to each cluster's spread, see
   ``roughen`` (particles.py);
4. a tight cloud that the scans keep contradicting starts over as a global localization
   (not AMCL's; see ``_restart_if_lost``);
5. while not localized (and, sparingly, while the scan fits poorly), a share of the particles
   is put on poses where the scan fits the map better than at the estimate (not AMCL's: sensor
   resetting, see ``_reseed_from_scan`` and posesearch.py);
6. while not localized, ``explore_heading`` names where to drive so that the heaviest
   clusters would see different scans (not AMCL's: active localization, explore.py); the
   controllers that localize before driving follow it (controllers/localizing.py).
The pose is the weighted mean of the heaviest cluster of particles (AMCL's choice, which stays
right while a global localization still has several candidates), composed with the odometry
motion since the last update; the covariance is that cluster's weighted sample covariance.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.config.localization import MclConfig
from pymunk_bot.localization.dynamic import excused_fit, short_returns
from pymunk_bot.localization.explore import Explorer, trace
from pymunk_bot.localization.motion import sample_motion
from pymunk_bot.localization.moving import MovingReturns
from pymunk_bot.localization.particles import (CLUSTER_BIN, cluster_labels, cluster_modes, kld_limit,
                        low_variance_indices, roughen, weighted_pose_stats)
from pymunk_bot.localization.posesearch import beam_log_pz, refine, search
from pymunk_bot.localization.se2 import between, compose, scan_points, transform_points, wrap

KLD_BIN = (0.5, 0.5, np.deg2rad(10.0))  # [m, m, rad] AMCL's histogram bins
CHUNK_ENDPOINTS = 1_000_000  # beam end points weighted at once (bounds temporary memory)
LOCALIZED_CLUSTER_WEIGHT = 0.9  # share of the belief one cluster must hold to drive on it
# Share of the scan's returns that must end within sigma_hit of the map from the estimate:
# measured 1.0 when right, 0.16-0.51 after a kidnapping in the office; 30 % is left for
# returns off things the map does not have.
LOCALIZED_SCAN_FIT = 0.7
# While not localized the scan is weighed as this many independent beams: the product of the
# used beams' pz raised to GLOBAL_BEAMS / beams (a tempered likelihood). The full product
# collapses a broad cloud on the first scan's best guess, AMCL's 1 + sum pz^3 barely tells the
# hypotheses apart (a factor of ~10 per scan); measured on generated offices and clutter rooms
# (10 seeds each, a global start), 5 converged in 17/20 within 20 s, 10 in 15/20, 20 in 8/20.
GLOBAL_BEAMS = 5.0
# Fewer returns than this left after leaving out the moving ones: the scan is weighed whole
# (moving.py); fewer left after leaving out the short ones (while tracking): the scan fit is
# not judged (dynamic.excused_fit), the last one stands. Returns short of the map are left out
# of the weighting however few are left: weighing them
# weighed the people who hid the walls (measured: warehouse, 10 walkers, seed 12, a 3.5 m
# LiDAR with 20 returns, more than 10 of them short: one scan fitted 40 %, the filter turned to
# global localization and settled 17 m away; leaving them out, it tracks to 2.1 cm).
MIN_KEPT_RETURNS = 10
# Updates in a row that a tight cloud may disagree with the scan before MCL starts over.
LOST_UPDATES = 3
# Reseeding from the scan (posesearch.py): while not localized, poses found on the map that
# explain the scan better (mean log pz) than the estimate does by RESEED_MARGIN, both polished
# alike, replace RESEED_FRACTION of the particles. While localized with a scan fit below
# SUSPECT_SCAN_FIT (a look-alike room settled on wrongly: fit 0.85-0.9), at most once per
# SUSPECT_PERIOD and only for a gain of SUSPECT_MARGIN: among people and other things the map
# lacks, poses elsewhere fit the clutter a little better (gains up to 0.085 seen in
# pedestrian_corridor, against 0.157 for the true pose beside a wrong room), and seeding them
# pulled the estimate off (3.2 cm error instead of 3 mm, and 6x the CPU: a search is ~25 ms).
SUSPECT_SCAN_FIT = 0.9
SUSPECT_MARGIN = 0.1  # mean log pz per beam
# ... and, in all, SUSPECT_EVIDENCE (a likelihood ratio of e^6, SUSPECT_MARGIN over the default
# 60 beams): with most beams on people and excused, the few left fit places elsewhere as well
# (measured: warehouse, 30 ORCA walkers, seed 0, 21 of 60 returns left while walkers pushed the
# robot: a pose 22 m away gained more than 0.1 per return, took the estimate at the next update
# and the robot drove 20 s on it).
SUSPECT_EVIDENCE = 6.0  # [nats] summed over the returns compared
SUSPECT_PERIOD = 1.0  # [s]
RESEED_FRACTION = 0.1
RESEED_MARGIN = 0.005  # mean log pz per beam a found pose must gain over the estimate
# Active localization (explore.py): while not localized, the heading in which the hypotheses
# (up to EXPLORE_MODES clusters of at least EXPLORE_MODE_WEIGHT of the belief) would see the
# most different scans; a localizing controller drives that way.
EXPLORE_MODES = 6
EXPLORE_MODE_WEIGHT = 0.02
EXPLORE_CLEARANCE = 0.1  # [m] a side of the robot, in the corridor its scan must show free


class MclLocalizer(Localizer):
    """Adaptive Monte Carlo localization against the scenario's map."""

    needs_map = True
    needs_lidar = True

    def __init__(self, config: MclConfig, context: LocalizerContext) -> None:
        super().__init__(config, context)
        if context.map is None:
            raise ValueError("mcl needs a map (the scenario's, or world.map)")
        self.rng = context.rng
        self.field = context.likelihood_field(config.laser_likelihood_max_dist)
        self._cell = context.map.resolution  # [m]
        if self.field.free_xy.shape[0] == 0:
            raise ValueError("mcl: the map has no free cell to place particles on")
        start = np.asarray(context.start_pose, dtype=float)
        if config.initial == "global":
            self.particles = self.random_poses(config.particles or config.max_particles)
        else:
            n = config.particles or config.max_particles
            self.particles = start + self.rng.normal(0.0, 1.0, (n, 3)) * np.asarray(config.initial_std)
            self.particles[:, 2] = wrap(self.particles[:, 2])
        self.weights = np.full(self.particles.shape[0], 1.0 / self.particles.shape[0])
        self.w_slow = self.w_fast = 0.0
        self.cluster_weight = 1.0 if config.initial == "known" else 0.0  # of the heaviest cluster
        self.updates = 0  # measurement updates done
        self.scan_fit = 1.0  # fit_at the estimate for the last scan weighed
        self._suspect_search = -math.inf  # [s] when a localized filter last searched the map
        self._contradicted = 0  # updates in a row with a tight cloud and a poor scan fit
        self.restarts = 0  # global restarts after a kidnapping (see _restart_if_lost)
        self.reseeded = 0  # particles put on poses found from the scan, in all
        self.moving_returns = 0  # returns of the last scan weighed found moving (moving.py)
        # scans, in all, that left too few returns (not short of the map) to judge the fit
        self.inconclusive_scans = 0
        # Where the robot fits (half its radius off the map's obstacles): where to search;
        # every free cell if the map is too tight for that.
        free = self.field.free_xy
        roomy = free[self.field.distance(free[None])[0] >= 0.5 * context.robot.radius]
        self._places = roomy if roomy.shape[0] else free
        # [rad, robot frame] where to drive to tell the hypotheses apart (explore.py); None
        # while localized or when they agree; kept in the odometry frame between updates
        self.explore_heading: float | None = None
        self._explorer = Explorer(context.robot.radius, EXPLORE_CLEARANCE)
        self._beam_mean: np.ndarray | None = None  # per particle: geometric mean pz of the last scan
        self._odom_at_update: np.ndarray | None = None  # odometry when the filter last moved
        # recent scans, to find returns of things that move (moving.py)
        self._moving = MovingReturns(config.moving_window, config.moving_margin, config.moving_blob,
                                    track=config.moving_track)
        self._filter_pose, self.covariance = weighted_pose_stats(self.particles, self.weights)
        self.pose = start.copy() if config.initial == "known" else self._filter_pose.copy()

    # ------------------------------------------------------------------ public
    def update(self, inputs: LocalizerInputs) -> None:
        odom = np.asarray(inputs.odometry, dtype=float)
        scan = inputs.scan
        fresh = scan is not None and abs(scan.time - inputs.time) < 1e-9
        if self._odom_at_update is None:
            if fresh:  # the first scan: weigh the initial cloud before anything moves
                self._odom_at_update = odom.copy()
                self._measure_and_resample(scan, self._filter_pose)
        else:
            moved = between(self._odom_at_update, odom)
            if fresh and (np.hypot(moved[0], moved[1]) >= self.config.update_min_d
                          or abs(moved[2]) >= self.config.update_min_a):
                c = self.config
                self.particles = sample_motion(
                    self.particles, self._odom_at_update, odom,
                    (c.alpha1, c.alpha2, c.alpha3, c.alpha4, c.alpha5), self.rng,
                    c.robot_model_type)
                predicted = compose(self._filter_pose, moved)
                self._odom_at_update = odom.copy()
                self._measure_and_resample(scan, predicted)
        if fresh and self.config.reject_moving:
            self._moving.observe(scan, odom)
        since = (np.zeros(3) if self._odom_at_update is None
                 else between(self._odom_at_update, odom))
        self.pose = compose(self._filter_pose, since)
        self.explore_heading = self._explorer.heading(odom)

    def debug(self) -> dict[str, Any]:
        return {"particles": self.particles.copy(), "weights": self.weights.copy(),
                "cluster_weight": self.cluster_weight}

    @property
    def localized(self) -> bool:
        """One cluster holds LOCALIZED_CLUSTER_WEIGHT of the belief, its spread is within the
        bounds (a global start is not, until the cloud has collapsed) and the last scan fits
        the map from the estimate (``scan_fit`` >= LOCALIZED_SCAN_FIT: a kidnapped robot's
        tight cloud does not)."""
        return (self.cluster_weight >= LOCALIZED_CLUSTER_WEIGHT
                and self.scan_fit >= LOCALIZED_SCAN_FIT and self.spread_within_bounds())

    def fit_at(self, pose: np.ndarray, scan, leave_out: np.ndarray | None = None) -> float:
        """The fraction of the scan's returns that end within ``sigma_hit`` of an obstacle of
        the map when seen from ``pose``: near 1 where the estimate is right, low where the map
        and the scan disagree (a kidnapping, a wrong global guess). 1.0 with no return.
        ``leave_out``: boolean per return (``scan_points`` order), returns not counted (those
        of moving things). (While tracking, ``scan_fit`` is this over the used beams with the
        returns short of the map excused: dynamic.excused_fit; a scan that leaves fewer than
        MIN_KEPT_RETURNS of them keeps the last fit.)"""
        points, _ = scan_points(scan)
        if leave_out is not None:
            points = points[~leave_out]
        if points.shape[0] == 0:
            return 1.0
        d = self.field.distance(transform_points(np.asarray(pose, dtype=float), points))
        return float(np.mean(d <= self.config.sigma_hit))

    def _short(self, pose: np.ndarray, points: np.ndarray, scan) -> np.ndarray:
        """Which end ``points`` (robot frame) of ``scan`` are short of the map from ``pose``."""
        return short_returns(self.field, pose, points, (scan.offset[0], scan.offset[1]),
                             scan.max_range, self.config.short_margin)

    def random_poses(self, count: int) -> np.ndarray:
        """Poses drawn uniformly over the map's free cells, any heading."""
        free = self.field.free_xy
        pick = free[self.rng.integers(0, free.shape[0], count)]
        xy = pick + self.rng.uniform(-0.5 * self._cell, 0.5 * self._cell, (count, 2))
        return np.column_stack([xy, self.rng.uniform(-np.pi, np.pi, count)])

    # ------------------------------------------------------------------ filter steps
    def _measure_and_resample(self, scan, predicted: np.ndarray) -> None:
        """Weigh by ``scan``, resample, estimate. ``predicted``: the estimate moved by the
        odometry, from which returns short of the map are found (while localized)."""
        c = self.config
        # Short of the map: only while tracking, as from a wrong pose it would hide the beams
        # that say so.
        reject = c.reject_short and self.localized
        all_points, index = scan_points(scan)
        used = self._used(scan, index)
        moving_all = np.zeros(index.size, dtype=bool)
        # Moving (moving.py): needs no pose, so while localizing; not while tracking, where a
        # push the odometry misses makes the walls look moving (warehouse, 30 walkers, seed 0:
        # localized on the right pose, then 20 s on a wrong one) and the test above serves.
        if c.reject_moving and not self.localized and self._odom_at_update is not None:
            moving_all = self._moving.flag(scan, self._odom_at_update)
            if np.count_nonzero(~moving_all[used]) < MIN_KEPT_RETURNS:
                moving_all[:] = False
        points, moving = all_points[used], moving_all[used]
        short = np.zeros(points.shape[0], dtype=bool)
        if reject and points.shape[0]:
            short = self._short(predicted, points, scan) & ~moving
        left_out = short | moving
        self.moving_returns = int(np.count_nonzero(moving_all))
        likelihood = self.scan_likelihood(scan, points[~left_out])
        weights = self.weights * likelihood
        total = weights.sum()
        if not (np.isfinite(total) and total > 0):
            weights = np.full(weights.size, 1.0)
            total = float(weights.size)
        w_avg = total / weights.size
        if self._beam_mean is not None:
            # The likelihood field's weights change scale with the model (the product while
            # localized, the sum until then): the recovery compares averages across scans, so
            # it averages a statistic of one scale, each particle's per-beam geometric mean pz.
            w_avg = float(self.weights @ self._beam_mean)
        if c.recovery_alpha_slow > 0 or c.recovery_alpha_fast > 0:
            self.w_slow = w_avg if self.w_slow == 0 else self.w_slow + c.recovery_alpha_slow * (w_avg - self.w_slow)
            self.w_fast = w_avg if self.w_fast == 0 else self.w_fast + c.recovery_alpha_fast * (w_avg - self.w_fast)
        self.weights = weights / total
        self.updates += 1
        if self.updates % c.resample_interval == 0:
            self._resample()
        self._filter_pose, self.covariance = self._cluster_estimate()
        if reject:  # the used beams, short and moving ones excused
            fits = self.field.distance(transform_points(self._filter_pose, points)) <= c.sigma_hit
            fit = excused_fit(fits, left_out, MIN_KEPT_RETURNS)
            # Too few returns left to judge (the robot wedged among people): the scan neither
            # confirms nor contradicts, and the last conclusive fit stands. The few are still
            # weighed: they hold the heading while the robot turns among people (tried: not
            # weighing them, the cloud widened by the odometry's noise, 3-9 deg off in the
            # warehouse with 30 ORCA walkers, seeds 2 and 18, and was lost: 78/80 runs).
            self.inconclusive_scans += fit is None
            if fit is not None:
                self.scan_fit = fit
        else:
            self.scan_fit = self.fit_at(self._filter_pose, scan, moving_all)
        self._restart_if_lost()
        if not self.localized:
            self._reseed_from_scan(scan, points[~moving], RESEED_MARGIN)
            self._explore(scan)
            return
        self._explorer.forget()
        if self.scan_fit < SUSPECT_SCAN_FIT and scan.time >= self._suspect_search + SUSPECT_PERIOD:
            self._suspect_search = scan.time
            kept = points[~left_out]
            self._reseed_from_scan(scan, kept, max(SUSPECT_MARGIN,
                                                   SUSPECT_EVIDENCE / max(kept.shape[0], 1)))

    def _reseed_from_scan(self, scan, points: np.ndarray, margin: float) -> None:
        """Sensor resetting (posesearch.py): put RESEED_FRACTION of the particles on poses
        that explain this scan better than the estimate, found anywhere on the map. A cloud
        settles only where it has particles; a global start or a kidnapping seldom has one
        near the truth (instrumented: none within 0.3 m / 10 deg in every failed run), and
        the cloud then settled on a look-alike room or aisle."""
        c = self.config
        z_rand = c.z_rand / scan.max_range
        found, score = search(self.field, points, self._places, self.rng, c.sigma_hit, c.z_hit, z_rand)
        if found.shape[0] == 0:
            return
        here = refine(self.field, self._filter_pose[None], points)[0]
        here_score = beam_log_pz(self.field, here[None], points, c.sigma_hit, c.z_hit, z_rand)[0]
        away = ((np.hypot(found[:, 0] - here[0], found[:, 1] - here[1]) > CLUSTER_BIN)
                | (np.abs(wrap(found[:, 2] - here[2])) > KLD_BIN[2]))
        better = found[away & (score > here_score + margin)]
        if better.shape[0] == 0:
            return
        n = self.particles.shape[0]
        slots = self.rng.choice(n, max(1, int(RESEED_FRACTION * n)), replace=False)
        self.particles[slots] = better[np.arange(slots.size) % better.shape[0]]
        self.weights[slots] = self.weights.mean()
        self.weights /= self.weights.sum()
        self.reseeded += slots.size

    def _explore(self, scan) -> None:
        """Active localization (explore.py) from the heaviest clusters of the belief."""
        labels = cluster_labels(self.particles)
        if labels is None or self._odom_at_update is None:
            self._explorer.forget()
            return
        modes, share = cluster_modes(self.particles, self.weights, labels, EXPLORE_MODE_WEIGHT,
                                     EXPLORE_MODES)
        self._explorer.update(self.field, modes, share, scan_points(scan)[0], scan.max_range,
                              self._odom_at_update, scan.time)

    def used_points(self, scan) -> np.ndarray:
        """End points (robot frame) of the ``max_beams`` beams, evenly spread, that returned:
        the ones the likelihood field weighs (bench/mcl_heading_probe.py probes them too)."""
        points, index = scan_points(scan)
        return points[self._used(scan, index)]

    def _used(self, scan, index: np.ndarray) -> np.ndarray:
        """Boolean per return (beam ``index``): which of ``scan``'s are the used beams'."""
        n_beams = np.asarray(scan.ranges).size
        step = max(1, (n_beams - 1) // (self.config.max_beams - 1))
        return index % step == 0

    def _restart_if_lost(self) -> None:
        """A tight cloud that the scans contradict LOST_UPDATES times in a row (a kidnapping, a
        wrong global guess) starts over as a global localization: ``max_particles`` over the
        free space. AMCL's recovery alone injects once (it resets w_slow and w_fast), a few
        random particles that rarely land near the truth; see docs/localization-journal.md."""
        c = self.config
        tight = self.cluster_weight >= LOCALIZED_CLUSTER_WEIGHT and self.spread_within_bounds()
        recovery = c.recovery_alpha_slow > 0 or c.recovery_alpha_fast > 0
        self._contradicted = self._contradicted + 1 if (
            recovery and tight and self.scan_fit < LOCALIZED_SCAN_FIT) else 0
        if self._contradicted >= LOST_UPDATES:
            self.particles = self.random_poses(c.max_particles)
            self.weights = np.full(c.max_particles, 1.0 / c.max_particles)
            self.cluster_weight = 0.0
            self.w_slow = self.w_fast = 0.0
            self._contradicted = 0
            self.restarts += 1

    def scan_likelihood(self, scan, points: np.ndarray | None = None) -> np.ndarray:
        """The per-particle weight factor for this scan: AMCL's 1 + sum of pz^3 over the used
        beams (``likelihood_field``); for ``likelihood_field_prob`` their product while
        localized, tempered to GLOBAL_BEAMS beams until then; ``beam``: _beam_likelihood
        (whose z_short handles returns short of the map per particle). ``points``: the
        robot-frame end points to weigh (default: the ``max_beams`` used ones)."""
        c = self.config
        if c.laser_model_type == "beam":
            n_beams = np.asarray(scan.ranges).size
            return self._beam_likelihood(scan, np.arange(0, n_beams, max(1, (n_beams - 1) // (c.max_beams - 1))))
        if points is None:
            points = self.used_points(scan)
        p = np.ones(self.particles.shape[0])
        self._beam_mean = None
        if points.shape[0] == 0:
            return p
        log_mean = np.empty(self.particles.shape[0])  # per particle: mean of log pz
        denom = 2.0 * c.sigma_hit ** 2
        z_rand = c.z_rand / scan.max_range
        chunk = max(1, CHUNK_ENDPOINTS // points.shape[0])
        # The product is for tracking: over a broad belief (a global start, a kidnapping) it
        # would collapse the cloud on the first scan's best guess, right or not; until the
        # filter is localized, the product tempered to GLOBAL_BEAMS beams weighs the hypotheses
        # (likelihood_field: AMCL's 1 + sum pz^3 throughout).
        sum_model = c.laser_model_type == "likelihood_field"
        weighed_beams = points.shape[0] if self.localized else GLOBAL_BEAMS
        for start in range(0, self.particles.shape[0], chunk):
            ends = transform_points(self.particles[start:start + chunk], points)
            d = self.field.distance(ends)
            pz = c.z_hit * np.exp(-d * d / denom) + z_rand
            log_mean[start:start + chunk] = np.log(pz).mean(axis=1)
            if sum_model:
                p[start:start + chunk] += (pz ** 3).sum(axis=1)
        self._beam_mean = np.exp(log_mean)
        if sum_model:
            return p
        log_p = log_mean * weighed_beams  # Nav2's likelihood_field_prob, tempered if not localized
        return np.exp(log_p - log_p.max())  # scaled so the best particle has weight 1

    def _beam_likelihood(self, scan, used: np.ndarray) -> np.ndarray:
        c = self.config
        ranges = np.asarray(scan.ranges, dtype=float)[used]
        angles = np.asarray(scan.angles, dtype=float)[used]
        mount = np.array([[scan.offset[0], scan.offset[1]]])
        p = np.ones(self.particles.shape[0])
        chunk = max(1, CHUNK_ENDPOINTS // used.size)
        for start in range(0, self.particles.shape[0], chunk):
            part = self.particles[start:start + chunk]
            origin = transform_points(part, mount)[:, 0, :]  # (n, 2)
            heading = part[:, 2:3] + angles[None, :]  # (n, m)
            expected = trace(self.field, origin, heading, scan.max_range)
            z = ranges[None, :] - expected
            pz = c.z_hit * np.exp(-z * z / (2.0 * c.sigma_hit ** 2))
            short = z < 0
            pz += np.where(short, c.z_short * c.lambda_short * np.exp(-c.lambda_short * ranges), 0.0)
            at_max = ranges >= scan.max_range
            pz += np.where(at_max, c.z_max, c.z_rand / scan.max_range)
            p[start:start + chunk] += (pz ** 3).sum(axis=1)
        return p

    def _resample(self) -> None:
        c = self.config
        n_max = c.max_particles
        draw = low_variance_indices(self.weights, n_max, self.rng)
        draw = draw[self.rng.permutation(n_max)]  # a prefix of a shuffled systematic draw is fair
        new = self.particles[draw]
        if self.w_slow > 0:
            w_diff = max(0.0, 1.0 - self.w_fast / self.w_slow)
            random = self.rng.random(n_max) < w_diff
            if random.any():
                new[random] = self.random_poses(int(random.sum()))
                self.w_slow = self.w_fast = 0.0
        count = self._kld_count(new)
        # Roughen only while the filter is not localized (a global start, a kidnapping): on
        # one tight cluster it would feed the spread along directions the scan cannot see.
        # (A uniform cloud is one 8-connected cluster of bins: its weight alone says nothing.)
        self.particles = new[:count] if self.localized else roughen(new[:count], self.rng)
        self.weights = np.full(count, 1.0 / count)

    def _kld_count(self, poses: np.ndarray) -> int:
        """How many of ``poses`` (in draw order) KLD-sampling keeps."""
        c = self.config
        keys = np.floor(poses / np.asarray(KLD_BIN)).astype(np.int64)
        _, first = np.unique(keys, axis=0, return_index=True)
        new_bin = np.zeros(poses.shape[0], dtype=np.int64)
        new_bin[first] = 1
        k = np.cumsum(new_bin)  # occupied bins after n particles
        n = np.arange(1, poses.shape[0] + 1)
        limit = np.where(k <= 1, c.max_particles, kld_limit(k, c.pf_err, c.pf_z))
        limit = np.clip(limit, c.min_particles, c.max_particles)
        enough = np.flatnonzero(n > limit)
        return int(n[enough[0]]) if enough.size else poses.shape[0]

    def _cluster_estimate(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean and covariance of the heaviest 8-connected cluster of 0.5 m (x, y) bins."""
        labels = cluster_labels(self.particles)
        if labels is None:  # particles strewn absurdly far: no clustering
            self.cluster_weight = 0.0
            return weighted_pose_stats(self.particles, self.weights)
        mass = np.bincount(labels, weights=self.weights)
        members = labels == int(np.argmax(mass))
        self.cluster_weight = float(mass.max() / mass.sum())
        return weighted_pose_stats(self.particles[members], self.weights[members])
