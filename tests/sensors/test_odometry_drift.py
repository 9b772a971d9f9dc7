"""Odometry drift statistics: the spread over many seeded runs is what the noise model predicts.

Model: each wheel's measured travel gains N(0, sigma^2 * |travel|), so over a straight drive of
D metres each wheel's error is a random walk w(s) with variance sigma^2 s. Along the track the
error is (w_L + w_R) / 2; the heading error is (w_R - w_L) / b; the cross-track error is the
integral of the heading error over the path. To first order:
    var(along) = sigma^2 D / 2
    var(theta) = 2 sigma^2 D / b^2
    var(cross) = 2 sigma^2 D^3 / (3 b^2)
    cov(cross, theta) = sigma^2 D^2 / b^2      (correlation sqrt(3) / 2)
The first order holds while the heading error stays small: the along-track error also loses
the cosine of the heading error, about sigma^2 D^2 / (2 b^2), which must stay far below its
standard deviation, i.e. sigma * D^1.5 / b^2 << 1 (0.07 for the values below).
With n runs a sample standard deviation is off by about 1 / sqrt(2 n) (one sigma).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot, scenario, wheels

from pymunk_bot import Simulation
from pymunk_bot.config import parse_scenario
from pymunk_bot.config.schema import OdometryConfig
from pymunk_bot.sensors.odometry import Odometry

TRACK = 0.3  # [m]


def predicted_covariance(sigma: float, distance: float, track: float) -> np.ndarray:
    """Closed-form covariance of (along, cross, theta) after a straight drive."""
    s2, d, b2 = sigma ** 2, distance, track ** 2
    return np.array([[s2 * d / 2, 0.0, 0.0],
                     [0.0, 2 * s2 * d ** 3 / (3 * b2), s2 * d ** 2 / b2],
                     [0.0, s2 * d ** 2 / b2, 2 * s2 * d / b2]])


def spread(errors: np.ndarray) -> tuple[np.ndarray, float]:
    """(standard deviations per column, correlation of columns 1 and 2)."""
    cov = np.cov(errors, rowvar=False)
    std = np.sqrt(np.diag(cov))
    return std, cov[1, 2] / (std[1] * std[2])


def correlations(cov: np.ndarray) -> np.ndarray:
    std = np.sqrt(np.diag(cov))
    return cov / np.outer(std, std)


def feed(odometry: Odometry, left: float, right: float, ticks: int) -> None:
    for _ in range(ticks):
        odometry.update(left, right)


@pytest.mark.slow  # end-to-end, several seconds: .ci/run runs it (-m slow)
def test_straight_drive_spread_matches_the_closed_form():
    sigma, distance, ticks, runs = 2e-4, 10.0, 100, 4000
    config = OdometryConfig(wheel_noise_std=sigma)
    ends, covariances = [], []
    for rng in np.random.default_rng(11).spawn(runs):
        odometry = Odometry(config, (0.0, 0.0, 0.0), TRACK, rng)
        feed(odometry, distance / ticks, distance / ticks, ticks)
        ends.append(odometry.pose - (distance, 0.0, 0.0))
        covariances.append(odometry.covariance)
    predicted = predicted_covariance(sigma, distance, TRACK)
    std, correlation = spread(np.array(ends))
    # 4000 runs: sampling error of a std about 1.1 %.
    assert std == pytest.approx(np.sqrt(np.diag(predicted)), rel=0.05)
    assert correlation == pytest.approx(math.sqrt(3) / 2, abs=0.02)
    # The covariance odometry reports (propagated tick by tick) is the same prediction.
    reported = np.mean(covariances, axis=0)
    assert np.diag(reported) == pytest.approx(np.diag(predicted), rel=0.02)
    assert correlations(reported) == pytest.approx(correlations(predicted), abs=0.02)


@pytest.mark.slow  # end-to-end, several seconds: .ci/run runs it (-m slow)
def test_arc_spread_matches_the_propagated_covariance():
    sigma, ticks, runs = 3e-3, 120, 4000
    left, right = 0.06, 0.1  # [m] per tick: about 2.3 rad of turn over 9.6 m
    config = OdometryConfig(wheel_noise_std=sigma)
    ends, covariances = [], []
    for rng in np.random.default_rng(12).spawn(runs):
        odometry = Odometry(config, (1.0, 2.0, 0.5), TRACK, rng)
        feed(odometry, left, right, ticks)
        ends.append(odometry.pose)
        covariances.append(odometry.covariance)
    empirical = np.cov(np.array(ends), rowvar=False)
    predicted = np.mean(covariances, axis=0)
    assert np.sqrt(np.diag(empirical)) == pytest.approx(np.sqrt(np.diag(predicted)), rel=0.05)
    assert correlations(empirical) == pytest.approx(correlations(predicted), abs=0.03)


@pytest.mark.slow  # end-to-end, several seconds: .ci/run runs it (-m slow)
def test_end_point_spread_over_seeded_simulation_runs_matches_the_model():
    """The real simulation: 300 seeded runs of a 10 m straight drive."""
    sigma, runs = 2e-4, 300
    config = parse_scenario(scenario(
        [robot([2, 10, 0.0], max_wheel_speed=2.0, odometry={"wheel_noise_std": sigma},
               controller=wheels(2.0, 2.0))]), "drift")
    errors, distances = [], []
    for seed in range(runs):
        sim = Simulation(config, seed=seed)
        sim.run(5.4)  # a 2/3 s ramp to 2 m/s, then 10 m in all
        r = sim.robots["r"]
        errors.append(r.odometry.pose - r.pose)
        distances.append(r.distance)
    assert np.ptp(distances) < 1e-9  # noise is in the estimate only: every run drives the same
    predicted = predicted_covariance(sigma, distances[0], TRACK)
    std, correlation = spread(np.array(errors))
    # 300 runs: sampling error of a std about 4 %.
    assert std == pytest.approx(np.sqrt(np.diag(predicted)), rel=0.10)
    assert correlation == pytest.approx(math.sqrt(3) / 2, abs=0.05)
    assert distances[0] == pytest.approx(10.1, abs=0.05)
