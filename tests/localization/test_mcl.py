"""Monte Carlo localization: tracking, global localization, KLD, resampling, bad input."""
import numpy as np
import pytest
from pydantic import ValidationError

import harness
from pymunk_bot.localization import MclConfig, MclLocalizer
from pymunk_bot.localization.particles import kld_limit, low_variance_indices
from pymunk_bot.localization.motion import sample_motion

# Tracking uses the defaults (issue 20: they must work on their own).
TRACKING: dict = {}


def test_defaults_are_nav2_amcls_but_the_documented_ones():
    c = MclConfig()
    # odometry noise and update steps differ from Nav2's (0.2 x 5, 0.25 m, 0.2 rad): issue 20
    assert (c.alpha1, c.alpha2, c.alpha3, c.alpha4, c.alpha5) == (0.02, 0.05, 0.02, 0.02, 0.02)
    assert (c.min_particles, c.max_particles, c.pf_err, c.pf_z) == (500, 2000, 0.05, 0.99)
    assert (c.update_min_d, c.update_min_a, c.resample_interval) == (0.1, 0.1, 1)
    assert (c.z_hit, c.z_short, c.z_max, c.z_rand) == (0.5, 0.05, 0.05, 0.5)
    assert c.sigma_hit == 0.1  # Nav2: 0.2, too flat in heading: issue 36
    assert (c.lambda_short, c.laser_likelihood_max_dist, c.max_beams) == (0.1, 2.0, 60)
    # Nav2's likelihood_field_prob (the product, while localized) and recovery on: issue 20
    assert c.laser_model_type == "likelihood_field_prob" and c.initial == "known"
    assert (c.recovery_alpha_slow, c.recovery_alpha_fast) == (0.001, 0.1)


def test_tracks_the_office_within_5_cm_and_2_degrees_despite_drifting_odometry():
    trial, loc, sim = harness.run(harness.office(seed=3),
                                  lambda ctx: MclLocalizer(MclConfig(**TRACKING), ctx), 25.0, seed=3)
    errors = trial.errors()
    odometry_error = np.hypot(*(sim.robots["r1"].odometry.pose[:2] - sim.robots["r1"].pose[:2]))
    assert errors["rmse"] <= 0.05 and errors["heading_rmse"] <= np.deg2rad(2.0), errors
    assert odometry_error > 5 * errors["rmse"]  # the odometry alone really drifts
    assert trial.collisions == 0
    debug = loc.debug()
    assert debug["particles"].shape == (debug["weights"].size, 3)
    assert debug["weights"].sum() == pytest.approx(1.0)
    assert 500 <= debug["weights"].size <= 2000  # KLD keeps between min and max


def test_global_localization_finds_the_robot_within_15_s():
    config = MclConfig(initial="global", max_particles=5000, recovery_alpha_slow=0.001,
                       recovery_alpha_fast=0.1)
    trial, _, _ = harness.run(harness.ros_map(seed=4, start_index=4),
                              lambda ctx: MclLocalizer(config, ctx), 16.0, seed=4, drive_on="truth")
    assert harness.converged(trial, 0.3, np.deg2rad(10.0)) <= 15.0


def test_the_beam_model_tracks_too():
    config = MclConfig(laser_model_type="beam", sigma_hit=0.05, update_min_d=0.1,
                       update_min_a=0.1, max_particles=500, min_particles=200)
    trial, _, _ = harness.run(harness.office(seed=1), lambda ctx: MclLocalizer(config, ctx), 8.0)
    assert trial.errors()["rmse"] <= 0.05


def test_kld_needs_more_particles_for_a_wider_belief():
    assert kld_limit(2, 0.05, 0.99) < kld_limit(50, 0.05, 0.99) < kld_limit(500, 0.05, 0.99)
    assert kld_limit(100, 0.01, 0.99) > kld_limit(100, 0.05, 0.99)  # stricter error, more samples


def test_low_variance_resampling_copies_particles_in_proportion_to_weight():
    rng = np.random.default_rng(0)
    weights = np.array([0.5, 0.25, 0.125, 0.125])
    counts = np.bincount(low_variance_indices(weights, 800, rng), minlength=4)
    np.testing.assert_array_equal(counts, [400, 200, 100, 100])  # exact, not just on average


def test_motion_model_spread_follows_the_alphas():
    rng = np.random.default_rng(5)
    start = np.zeros((20000, 3))
    old, new = np.zeros(3), np.array([1.0, 0.0, 0.0])  # 1 m straight ahead
    exact = sample_motion(start, old, new, (0, 0, 0, 0, 0), rng)
    np.testing.assert_allclose(exact, np.tile(new, (20000, 1)), atol=1e-12)
    moved = sample_motion(start, old, new, (0.0, 0.0, 0.04, 0.0, 0.0), rng)
    assert moved[:, 0].std() == pytest.approx(0.2, rel=0.05)  # sqrt(alpha3) * 1 m
    assert np.abs(moved[:, 2]).max() < 1e-12  # no rotation noise asked for
    backwards = sample_motion(start, old, -new, (0.1, 0.0, 0.0, 0.0, 0.0), rng)
    assert np.abs(backwards[:, 2]).max() < 1e-9  # reversing is not a half turn


def test_bad_particle_counts_are_refused_with_the_limit():
    with pytest.raises(ValidationError, match="less than or equal to 100000"):
        MclConfig(max_particles=10**7)
    with pytest.raises(ValidationError, match=r"min_particles \(3000\) must be <= max_particles \(2000\)"):
        MclConfig(min_particles=3000)
    with pytest.raises(ValidationError, match="Extra inputs"):
        MclConfig(alpha6=0.1)


def test_mcl_without_a_map_is_refused():
    sim, _, _ = harness.office()
    from pymunk_bot.localization.trial import make_context
    with pytest.raises(ValueError, match="mcl needs a map"):
        MclLocalizer(MclConfig(), make_context(sim, "r1", 0, None))


def test_roughening_a_cloud_of_equal_headings_gives_finite_poses():
    # The mean resultant of equal headings rounds to just above 1: log > 0 made the circular
    # std NaN, and every particle NaN with it (seen in global runs of the robustness bench).
    from pymunk_bot.localization.particles import roughen

    poses = np.tile([1.0, 2.0, 0.3], (1000, 1))
    assert np.isfinite(roughen(poses, np.random.default_rng(0))).all()


def test_a_point_inside_a_thick_obstacle_is_as_far_from_the_map_as_its_surface():
    # A 2 m thick shelf (x in [2, 4] m) in a 6 x 2 m room, 5 cm cells. A beam stops at the
    # shelf's face, so an end point 0.4 m inside it comes from an estimate 0.4 m off: the field
    # must say so (it read 0 inside, and MCL slid 0.5 m into Nav2's warehouse shelves).
    from pymunk_bot.localization.likelihood import LikelihoodField
    from pymunk_bot.maps.grid import OccupancyGrid

    data = np.zeros((40, 120), dtype=np.int8)
    data[:, 40:80] = 100
    field = LikelihoodField(OccupancyGrid(data, 0.05), max_dist=2.0)
    assert field.distance(np.array([[2.4, 1.0]]))[0] == pytest.approx(0.4, abs=0.02)  # inside
    assert field.distance(np.array([[1.6, 1.0]]))[0] == pytest.approx(0.4, abs=0.02)  # outside
    assert field.distance(np.array([[3.0, 1.0]]))[0] == pytest.approx(1.0, abs=0.02)  # the middle
    assert field.distance(np.array([[2.0, 1.0]]))[0] <= 0.02  # on the face
