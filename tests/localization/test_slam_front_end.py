"""Issue 20, second pass: SLAM's front end on generated offices with typical odometry.

Instrumented before (office seed 2: 180 beams, 5 m, 2.5 cm noise): each keyframe's match
slid 1-4 cm backwards along the route, and the error grew from 2.5 to 15 cm with no loop to
close. The fixes: line fits over the whole submap (normals from a point's two neighbours in
its own scan were tilted by ~6 deg), Cauchy's kernel instead of Huber's (points where the
reference has not yet seen anything pulled the match back with a constant force) and the
odometry as a prior of the match. ATE <= 5 cm on generated offices: 7 of 10 before, 10 of 10.
"""
from __future__ import annotations

import numpy as np
import pytest

from bench.localization_robustness import run_one
from harness import scan_of_segments
from pymunk_bot.localization.icp import Reference, icp
from pymunk_bot.localization.odometry_trust import OdometryTrust, scan_only
from pymunk_bot.localization.se2 import compose, transform_points
from pymunk_bot.localization.slam import MATCH_INLIERS, front_end_accepts


def test_line_fits_over_overlapping_noisy_scans_give_true_normals():
    rng = np.random.default_rng(0)
    # ten scans of the same wall (y = 2), 2.5 cm range noise, points 1-2 cm apart in all
    x = np.concatenate([np.linspace(0.0, 3.0, 150) + rng.uniform(0, 0.02) for _ in range(10)])
    wall = np.column_stack([x, 2.0 + rng.normal(0.0, 0.025, x.size)])
    ref = Reference.surfaces(wall)
    assert ref.points.shape[0] > 20
    tilt = np.degrees(np.arcsin(np.abs(ref.normals[:, 0])))
    assert np.median(tilt) < 2.0
    assert np.abs(ref.points[:, 1] - 2.0).max() < 0.03  # the fits lie on the wall


def test_the_odometry_prior_holds_a_corridor_where_the_scan_cannot():
    # Two long parallel walls: the scan fixes y and the heading, not x. From a guess 3 cm off
    # in x, the match with the odometry prior stays at the guess; across, it finds the walls.
    rng = np.random.default_rng(1)
    x = np.linspace(-4.0, 4.0, 400)
    walls = np.vstack([np.column_stack([x, np.full_like(x, 1.0)]),
                       np.column_stack([x, np.full_like(x, -1.0)])])
    ref = Reference.surfaces(walls + rng.normal(0.0, 0.01, walls.shape))
    scan = walls[::3] + rng.normal(0.0, 0.01, walls[::3].shape)
    guess = np.array([0.03, 0.04, 0.01])  # truth: (0, 0, 0)
    step = np.array([0.2, 0.0, 0.0])
    last = guess - np.array([0.2 * np.cos(0.01), 0.2 * np.sin(0.01), 0.0])
    predicted, prior = OdometryTrust().predict(last, step)
    assert np.allclose(predicted, guess)
    match = icp(ref, scan, guess, prior=prior)
    assert match.ok
    assert abs(match.pose[1]) < 0.01 and abs(match.pose[2]) < 0.005
    assert abs(match.pose[0] - guess[0]) < 0.01


def test_slam_keeps_to_5_cm_on_the_office_whose_front_end_drifted():
    out = run_one("slam", "office", "typical", 2)
    assert out is not None and not out.error
    assert out.rmse <= 0.05, out.line()
    assert out.map_precision >= 0.9, out.line()


def test_one_sparse_scan_has_surfaces_to_match():
    # The first keyframe's reference is one scan: 180 beams see a wall 5 m away 17 cm apart,
    # fewer than a line fit needs within 20 cm. The fits widen there (the first match of
    # warehouse seed 2 had no surface at all and took the odometry's heading for good).
    rng = np.random.default_rng(3)
    bearings = np.radians(np.arange(-30.0, 30.0, 2.0))
    ranges = 5.0 / np.cos(bearings) + rng.normal(0.0, 0.025, bearings.size)
    wall = np.column_stack([ranges * np.cos(bearings), ranges * np.sin(bearings)])
    ref = Reference.surfaces(wall)
    assert ref.points.shape[0] >= wall.shape[0] // 2
    assert np.median(np.degrees(np.arccos(np.abs(ref.normals[:, 0])))) < 3.0  # facing x


def _match_of(trust: OdometryTrust, last: np.ndarray, step: np.ndarray, truth_step: np.ndarray,
              scan_sd: tuple[float, float, float], rng: np.random.Generator) -> None:
    """One keyframe: the scan finds the true pose to within ``scan_sd`` along the robot's
    forward, left and turn directions; the match is the MAP fusion with the trust's prior."""
    predicted, prior = trust.predict(last, step)
    truth = compose(last, truth_step)
    c, s = np.cos(predicted[2]), np.sin(predicted[2])
    axes = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    scan_cov = axes.T @ np.diag(np.square(scan_sd)) @ axes
    scan_pose = truth + axes.T @ (rng.normal(0.0, 1.0, 3) * scan_sd)
    scan_info = np.linalg.inv(scan_cov)
    covariance = np.linalg.inv(scan_info + prior)
    pose = predicted + covariance @ (scan_info @ (scan_pose - predicted))
    trust.learn(step, predicted, pose, covariance, prior)


def _drive_straight(noise: float, scan_sd: tuple[float, float, float],
                    rng: np.random.Generator) -> tuple[OdometryTrust, np.ndarray]:
    """40 keyframes 25 cm apart, straight ahead, from odometry that reports 3 % less travel
    (plus ``noise`` [m] per step): the trust that learned from them and the last true pose."""
    trust = OdometryTrust()
    last = np.zeros(3)
    driven = np.array([0.25, 0.0, 0.0])
    for _ in range(40):
        reported = driven * np.array([0.97, 1.0, 1.0]) + np.array([rng.normal(0, noise), 0, 0])
        _match_of(trust, last, reported, driven, scan_sd, rng)
        last = compose(last, driven)
    return trust, last


def test_the_odometry_trust_learns_a_robot_whose_wheels_read_short():
    # Odometry that reports 3 % less travel than driven, 1 mm of noise per 25 cm step; the
    # scan pins every direction to 1 mm. The trust finds the 3 % and narrows its prior from
    # an uncalibrated robot's (2 cm per step) to a few millimetres.
    trust, last = _drive_straight(0.001, (0.001, 0.001, 0.0005), np.random.default_rng(4))
    assert abs(trust.travel_correction - 0.03 / 0.97) < 0.005
    _, prior = trust.predict(last, np.array([0.25, 0.0, 0.0]))
    assert 1.0 / np.sqrt(prior[0, 0]) < 0.005  # [m] the prior's forward sd


def test_the_odometry_trust_keeps_its_prior_where_the_scan_pins_nothing():
    # A corridor: the scan fixes the sideways direction and the heading, never the forward
    # one. The forward error of the odometry is then never sampled: no correction is made up.
    trust, _ = _drive_straight(0.0, (10.0, 0.001, 0.0005), np.random.default_rng(5))
    assert trust.travel_correction == 0.0


@pytest.mark.parametrize("family, profile, seed", [
    # Nav2's warehouse map, seed 9 (270 beams, 8 m): the first keyframe's match had too few
    # surfaces, took the odometry's 0.7 deg heading error, and the estimate drifted to 8 cm.
    ("warehouse", "typical", 9),
    # Nav2's depot map, seed 5 (270 beams, 5 m): after a turn, 12 keyframes in a row saw
    # 0.18-0.46 of their points on the submap; their matches (the first within 0.2 deg) were
    # rejected, the keyframes took the odometry's predictions, 25 deg off by the twelfth, and
    # the estimate ended 60 cm off.
    ("depot", "uncalibrated", 5),
])
def test_slam_keeps_to_5_cm_on_the_real_map_where_matches_were_lost(family, profile, seed):
    out = run_one("slam", family, profile, seed)
    if out is None:
        pytest.skip(f"the shared {family} map is not beside the checkout")
    assert not out.error
    assert out.rmse <= 0.05, out.line()
    assert out.map_precision >= 0.9, out.line()


def test_a_match_that_sees_mostly_new_walls_is_kept_when_the_odometry_explains_it():
    # A robot turns to face walls its submap has not seen: under half of its points land on
    # the submap. Its odometry, an uncalibrated robot's, put the heading 5 deg off over the
    # step. The match finds the true heading; the front end keeps it because the prior's
    # uncertainty explains the correction (before, it took the prediction, 5 deg off, and
    # every later match inherited it: the Nav2 depot, uncalibrated, seed 5, ATE 60 cm).
    seen = [(2.0, -2.0, 2.0, 2.0), (-0.5, 2.0, 2.0, 2.0)]  # what the submap holds
    room = seen + [(-2.0, 2.0, -0.5, 2.0), (-2.0, -2.0, -2.0, 2.0), (-2.0, -2.0, 2.0, -2.0)]
    ref = Reference.surfaces(scan_of_segments(seen, noise=0.005))
    truth = np.array([0.1, 0.05, np.radians(120.0)])
    scan = scan_of_segments(room, truth, noise=0.005, rng=np.random.default_rng(7))
    step = np.array([0.15, 0.0, np.radians(120.0)])  # from the origin, turning left
    _, prior = OdometryTrust().predict(np.zeros(3), step)
    predicted = np.array([truth[0], truth[1], truth[2] + np.radians(5.0)])
    match = icp(ref, scan, predicted, prior=prior)
    assert match.ok and match.inliers < MATCH_INLIERS
    assert abs(np.degrees(match.pose[2] - truth[2])) < 0.3
    assert front_end_accepts(match, predicted, prior)
    # the same correction against a prior a hundred times narrower is not explained
    assert not front_end_accepts(match, predicted, prior * 1e4)


def test_what_the_scan_alone_said_is_read_back_from_a_prior_held_match():
    # An instrument's view (bench.slam_heading_probe): a match held by an odometry prior 2 deg
    # off in heading lands between the two; scan_only recovers the scan's own pose and
    # covariance, so the prior's pull on the heading can be told from the scan's error.
    predicted = np.array([1.0, 2.0, 0.5])
    scan_pose = np.array([1.01, 1.99, 0.5 - np.radians(2.0)])
    scan_cov = np.diag([0.004, 0.002, np.radians(0.5)]) ** 2
    prior = np.diag([1.0 / 0.015 ** 2, 1.0 / 0.015 ** 2, 1.0 / np.radians(2.6) ** 2])
    covariance = np.linalg.inv(np.linalg.inv(scan_cov) + prior)
    pose = predicted + covariance @ (np.linalg.inv(scan_cov) @ (scan_pose - predicted))
    assert abs(pose[2] - scan_pose[2]) > np.radians(0.05)  # the prior pulled the heading
    offset, recovered = scan_only(pose, covariance, predicted, prior)
    assert np.allclose(predicted + offset, scan_pose, atol=1e-9)
    assert np.allclose(recovered, scan_cov, rtol=1e-6)


def _racks() -> list[tuple[float, float, float, float]]:
    """A 12 x 8 m room with two rows of three racks (1.3 x 0.6 m): wall segments (x0, y0, x1, y1)."""
    def box(x0: float, y0: float, x1: float, y1: float) -> list:
        c = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        return [(*c[i], *c[(i + 1) % 4]) for i in range(4)]
    walls = box(0.0, 0.0, 12.0, 8.0)
    for x0 in (2.0, 4.5, 7.0):
        walls += box(x0, 2.0, x0 + 1.3, 2.6) + box(x0, 5.0, x0 + 1.3, 5.6)
    return walls


def test_exact_scans_among_corners_match_exactly():
    # Rack ends and corners fitted as lines, weighed as walls, turned each match a little: a
    # scan matched to the ten before it at their true poses, no noise, 180 beams at 3.5 m,
    # along a row of racks and round its end: 0.030 deg RMS, -0.25 deg over the 59 matches
    # (weighed by how thin a line each fit is: 0.003 deg RMS, +0.02 deg).
    walls = _racks()
    poses = [np.array([1.0 + 0.2 * k, 4.0, 0.0]) for k in range(40)]
    poses += [np.array([9.0 + 0.5 * np.sin(np.radians(6 * k)), 4.5 - 0.5 * np.cos(np.radians(6 * k)),
                        np.radians(6 * k)]) for k in range(1, 16)]
    poses += [np.array([9.5, 4.5 + 0.2 * k, np.pi / 2]) for k in range(1, 15)]
    scans = [scan_of_segments(walls, p, beams=180, max_range=3.5, noise=0.0) for p in poses]
    errors = []
    for j in range(10, len(poses)):
        ref = Reference.surfaces(np.concatenate([transform_points(poses[k], scans[k])
                                                 for k in range(j - 10, j)]))
        match = icp(ref, scans[j], poses[j] + np.array([0.02, -0.02, np.radians(0.5)]))
        assert match.ok
        errors.append(np.degrees(match.pose[2] - poses[j][2]))
    errors = np.array(errors)
    assert np.sqrt(np.mean(errors ** 2)) < 0.01  # [deg]
    assert abs(errors.sum()) < 0.1  # [deg] what a chain of such matches adds up
