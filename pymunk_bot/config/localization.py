"""Sections of the built-in localizers and of mapping (``localization: <name>`` or
``{type: <name>, ...}``, ``mapping: {...}``). Every field has physical bounds; particle counts
are bounded so that memory stays sane. docs/localization.md lists every key with its unit and
default; keep them in step.

MCL's keys are ROS / Nav2 AMCL's parameter names and meanings, with Nav2's defaults except
the odometry noise (alpha1-5) and the update thresholds; docs/localization.md says why.
"""
from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from pymunk_bot.config.types import Float, Int, NonNegativeFloat, Section


class GroundTruthLocalizerConfig(Section):
    """The controller sees the true pose (no localization error: for tests and baselines)."""

    type: Literal["ground_truth"]


class OdometryLocalizerConfig(Section):
    """The controller sees dead reckoning from the wheel encoders (drifts like a real robot's)."""

    type: Literal["odometry"]


class PythonLocalizerConfig(Section):
    """A user's own localizer class, imported from ``class_path`` ('package.module:Class'):
    a :class:`pymunk_bot.localization.Localizer` subclass built as ``Class(config, context)``."""

    type: Literal["python"]
    class_path: str
    params: dict[str, Any] = {}  # handed to the class as ``config.params``


MAX_PARTICLES_LIMIT = 100_000  # ~2.4 MB of particles; a 60-beam update is done in chunks
MAX_MAP_CELLS = 16_000_000  # cells of a built occupancy grid (e.g. 200 x 200 m at 5 cm)
LOCALIZER_MAP_RESOLUTION = 0.05  # [m] of the prebuilt occupancy grid localizers are given

Alpha = Annotated[Float, Field(ge=0.0, le=10.0)]
Weight = Annotated[Float, Field(ge=0.0, le=1.0)]
ParticleCount = Annotated[Int, Field(ge=1, le=MAX_PARTICLES_LIMIT)]
StdVec3 = tuple[Annotated[Float, Field(ge=0.0, le=100.0)], Annotated[Float, Field(ge=0.0, le=100.0)],
                Annotated[Float, Field(ge=0.0, le=math.pi)]]
Distance = Annotated[Float, Field(gt=0.0, le=100.0)]  # [m]


class MclConfig(Section):
    """Monte Carlo localization (adaptive, KLD-sampling), ROS AMCL's parameters."""

    type: Literal["mcl"] = "mcl"
    particles: ParticleCount | None = None  # initial count; None = max_particles (as AMCL)
    initial: Literal["known", "global"] = "known"  # known: around the true start pose
    initial_std: StdVec3 = (0.1, 0.1, 0.1)  # [m, m, rad] spread around the start pose (known)
    robot_model_type: Literal["diff", "omni"] = "diff"
    # Odometry noise as AMCL defines it (variance ratios, motion.py). Nav2's 0.2 (a std of 45 %
    # of each motion) diffuses the cloud metres along an aisle the scan cannot fix; ours cover
    # an uncalibrated robot's 2-3 % and wheel noise with margin (docs/localization.md).
    alpha1: Alpha = 0.02  # rotation noise from rotation
    alpha2: Alpha = 0.05  # rotation noise from translation
    alpha3: Alpha = 0.02  # translation noise from translation
    alpha4: Alpha = 0.02  # translation noise from rotation
    alpha5: Alpha = 0.02  # strafe noise from translation (omni only)
    min_particles: ParticleCount = 500
    max_particles: ParticleCount = 2000
    pf_err: Annotated[Float, Field(gt=0.0, lt=1.0)] = 0.05  # KLD: max error of the sampled belief
    pf_z: Annotated[Float, Field(gt=0.0, le=10.0)] = 0.99  # KLD: the normal quantile (as AMCL uses it)
    # Nav2: 0.25 m / 0.2 rad. The motion noise per update grows with the step squared, so per
    # metre it grows with the step: shorter steps diffuse less and fold in more scans.
    update_min_d: Annotated[Float, Field(ge=0.0, le=100.0)] = 0.1  # [m] travel before an update
    update_min_a: Annotated[Float, Field(ge=0.0, le=2 * math.pi)] = 0.1  # [rad] turn before an update
    resample_interval: Annotated[Int, Field(ge=1, le=1000)] = 1  # updates between resamplings
    # Nav2's default is likelihood_field (1 + sum pz^3), too weak to hold a cloud where the
    # scan sees one wall (docs/localization.md); likelihood_field_prob is Nav2's product of pz.
    laser_model_type: Literal["likelihood_field", "likelihood_field_prob", "beam"] = "likelihood_field_prob"
    z_hit: Weight = 0.5
    z_short: Weight = 0.05  # beam model only
    z_max: Weight = 0.05  # beam model only
    z_rand: Weight = 0.5
    # [m] (Nav2: 0.2) the end point's error: 0.2 made the likelihood's heading curvature a
    # one-scan std of 2.6-2.8 deg where the scan fixes it to 0.35 deg (docs/localization-journal.md)
    sigma_hit: Annotated[Float, Field(ge=0.001, le=10.0)] = 0.1
    lambda_short: Annotated[Float, Field(gt=0.0, le=100.0)] = 0.1  # [1/m], beam model only
    laser_likelihood_max_dist: Distance = 2.0  # [m] distance field cap
    max_beams: Annotated[Int, Field(ge=2, le=10_000)] = 60
    # Not AMCL's: while localized, returns ending more than short_margin before the map's
    # surface along their beam (seen from the estimate: people, things the map lacks) are left
    # out of the likelihood-field models and of the scan fit (localization/dynamic.py).
    reject_short: bool = True
    short_margin: Annotated[Float, Field(ge=0.0, le=100.0)] = 0.3  # [m]
    # Not AMCL's: returns of things that moved (people walking), found with no map pose by
    # comparing each scan with the last moving_window seconds of scans through the odometry
    # (a return where an earlier beam reached more than moving_margin beyond it; a blob of
    # returns at most moving_blob across that holds one) are left out of the weighting, the
    # scan seeding and the scan fit while not localized (localization/moving.py).
    reject_moving: bool = True
    moving_window: Annotated[Float, Field(gt=0.0, le=10.0)] = 1.0  # [s]
    moving_margin: Annotated[Float, Field(ge=0.0, le=100.0)] = 0.2  # [m]
    moving_blob: Annotated[Float, Field(ge=0.0, le=10.0)] = 0.8  # [m]; 0: returns one by one
    # a return within moving_track of one seen moving in the last moving_window is moving
    # too (a walker that stops or walks away along the beam); 0: no memory
    moving_track: Annotated[Float, Field(ge=0.0, le=10.0)] = 0.5  # [m]
    # AMCL's recovery, on (Nav2: 0, off): a kidnapped robot or a wrong global guess needs it;
    # with it on, tracking succeeded as often (robustness benchmark, docs/localization-journal.md).
    recovery_alpha_slow: Weight = 0.001  # 0 (both) disables recovery
    recovery_alpha_fast: Weight = 0.1

    @model_validator(mode="after")
    def _consistent(self) -> "MclConfig":
        if self.min_particles > self.max_particles:
            raise ValueError(f"min_particles ({self.min_particles}) must be <= max_particles "
                             f"({self.max_particles})")
        if self.particles is not None and self.particles > self.max_particles:
            raise ValueError(f"particles ({self.particles}) must be <= max_particles "
                             f"({self.max_particles})")
        if self.z_hit + self.z_rand + self.z_short + self.z_max <= 0.0:
            raise ValueError("z_hit, z_short, z_max and z_rand must not all be 0")
        return self


class EkfConfig(Section):
    """EKF localization: odometry prediction, scan-to-map matching as the measurement."""

    type: Literal["ekf"] = "ekf"
    initial_std: StdVec3 = (0.05, 0.05, 0.05)  # [m, m, rad] around the true start pose
    # Random (white) odometry noise: variance grows with the distance and angle moved.
    trans_noise: Annotated[Float, Field(ge=0.0, le=1.0)] = 0.03  # [m/sqrt(m)] per metre driven
    rot_noise: Annotated[Float, Field(ge=0.0, le=1.0)] = 0.1  # [rad/sqrt(m)] per metre driven
    turn_noise: Annotated[Float, Field(ge=0.0, le=1.0)] = 0.1  # [rad/sqrt(rad)] per radian turned
    # Systematic error of an uncalibrated robot (wheel radii, track width), as a fraction of
    # each motion; folded in over each interval between scan corrections (see ekf.py).
    calibration_error: Annotated[Float, Field(ge=0.0, le=0.5)] = 0.03
    # Consecutive good matches refused by the gate before the filter admits it is lost and
    # widens its covariance by the disagreement (no lock-out).
    gate_patience: Annotated[Int, Field(ge=1, le=1000)] = 5
    max_dist: Distance = 1.0  # [m] distance-field cap for matching
    # Returns ending more than short_margin before the map's surface seen from the predicted
    # pose (people, things the map lacks) are left out of the match (localization/dynamic.py).
    reject_short: bool = True
    short_margin: Annotated[Float, Field(ge=0.0, le=100.0)] = 0.3  # [m]
    huber: Distance = 0.1  # [m] residuals beyond this count linearly (robust to clutter)
    iterations: Annotated[Int, Field(ge=1, le=100)] = 10  # Gauss-Newton iterations per match
    max_beams: Annotated[Int, Field(ge=3, le=10_000)] = 120
    match_cov_scale: Annotated[Float, Field(ge=1.0, le=1e6)] = 3.0  # inflates the match covariance
    map_std: Annotated[Float, Field(ge=0.0, le=10.0)] = 0.0  # [m] how far off the map's walls may be
    gate: Annotated[Float, Field(gt=0.0, le=1e6)] = 16.27  # Mahalanobis gate (chi^2_3, 99.9 %)


class SlamConfig(Section):
    """Pose-graph SLAM: scan-to-map matching, loop closures, map rebuilt from optimized poses."""

    type: Literal["slam"] = "slam"
    resolution: Annotated[Float, Field(ge=0.01, le=1.0)] = 0.05  # [m] map cell size
    keyframe_d: Annotated[Float, Field(gt=0.0, le=10.0)] = 0.2  # [m] travel between keyframes
    keyframe_a: Annotated[Float, Field(gt=0.0, le=math.pi)] = 0.2  # [rad] turn between keyframes
    loop_radius: Distance = 1.5  # [m] candidates: keyframes the robot could be this near
    loop_min_travel: Distance = 5.0  # [m] travelled since a keyframe before it can close a loop
    loop_min_inliers: Weight = 0.7  # fraction of scan points that must match a loop closure
    loop_kernel: Annotated[Float, Field(gt=0.0, le=1e6)] = 3.0  # Cauchy scale of loop edges [chi]
    max_pair: Distance = 0.3  # [m] ICP pairs a point with a reference point at most this far
    huber: Distance = 0.05  # [m] scale of the ICP's robust (Cauchy) kernel
    iterations: Annotated[Int, Field(ge=1, le=100)] = 20  # ICP iterations per match
    max_beams: Annotated[Int, Field(ge=3, le=10_000)] = 180
    optimize_every: Annotated[Int, Field(ge=1, le=10_000)] = 1  # loop closures between optimizations
    max_keyframes: Annotated[Int, Field(ge=10, le=100_000)] = 20_000  # then odometry only
    margin: NonNegativeFloat = 1.0  # [m] map extent beyond the arena
    # Returns of things that move (people) are left out of the keyframe's match and of what it
    # adds to the front end's submaps (slam.py): returns that entered space the last
    # moving_window seconds of scans saw free (reject_moving) or that lie in space the submap's
    # keyframes saw free (reject_free), by moving.py's test (margin, blob: MCL's keys), unless
    # SLAM's map holds a surface within surface_radius.
    reject_moving: bool = True
    moving_window: Annotated[Float, Field(gt=0.0, le=10.0)] = 1.0  # [s]
    moving_margin: Annotated[Float, Field(ge=0.0, le=100.0)] = 0.2  # [m]
    moving_blob: Annotated[Float, Field(ge=0.0, le=10.0)] = 0.8  # [m]; 0: returns one by one
    reject_free: bool = True
    surface_radius: Annotated[Float, Field(ge=0.0, le=1.0)] = 0.1  # [m]
    # Long straight walls as landmarks of the pose graph (walls.py): each keyframe's walls tie
    # its heading to the landmark's direction at the graph's optimizations. Every slam_revisit
    # row of the robustness benchmark gains or holds its runs within 5 cm (docs/localization-journal.md).
    wall_landmarks: bool = True


class MappingConfig(Section):
    """Occupancy-grid mapping from LiDAR with known poses (log-odds, inverse sensor model)."""

    resolution: Annotated[Float, Field(ge=0.01, le=1.0)] = 0.05  # [m] cell size
    hit_probability: Annotated[Float, Field(gt=0.5, lt=1.0)] = 0.7  # a cell where a beam ends
    miss_probability: Annotated[Float, Field(gt=0.0, lt=0.5)] = 0.4  # a cell a beam crosses
    min_probability: Annotated[Float, Field(gt=0.0, lt=0.5)] = 0.12  # clamp: a free cell can still
    max_probability: Annotated[Float, Field(gt=0.5, lt=1.0)] = 0.97  # ... turn occupied, and back
    margin: NonNegativeFloat = 1.0  # [m] extent beyond the arena (its walls lie outside it)
    # A cell held occupied that a beam crosses has its log-odds scaled by this before the miss
    # (1: plain log-odds): walkers are not burned into the map (mapping.py)
    clear_decay: Annotated[Float, Field(ge=0.0, le=1.0)] = 0.2
    rate: Annotated[Float, Field(gt=0.0, le=1000.0)] | None = None  # [Hz]; None = every scan
