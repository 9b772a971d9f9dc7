"""The car-like drive: exact circles through the rear axle, limits, walls, crates, odometry."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot

from pymunk_bot.config.errors import ScenarioError

CAR = {"drive": "ackermann", "wheelbase": 0.33, "max_steer": 0.5, "max_speed": 2.0,
       "footprint": {"type": "box", "size": [0.5, 0.3], "center": [0.165, 0.0]}}


def fit_circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    a = np.c_[2 * points, np.ones(len(points))]
    c = np.linalg.lstsq(a, (points ** 2).sum(axis=1), rcond=None)[0]
    return c[:2], math.sqrt(c[2] + c[0] ** 2 + c[1] ** 2)


def circle_of(sim, car, v, omega, settle=2.0, seconds=2.0):
    car.set_velocity(v, omega)
    sim.run(settle)
    points = []
    for _ in range(round(seconds / sim.dt)):
        sim.step()
        points.append(car.pose[:2].copy())
    return fit_circle(np.array(points))


def test_steering_beyond_the_limit_drives_the_tightest_circle_exactly(make_sim):
    sim = make_sim([robot([10, 10, 0], name="car", **CAR)])
    car = sim.robots["car"]
    _, radius = circle_of(sim, car, 1.0, 10.0)
    assert radius == pytest.approx(0.33 / math.tan(0.5), abs=1e-6)
    assert car.drive.steering_angle == pytest.approx(0.5)


def test_circle_radius_is_v_over_omega_through_the_rear_axle(make_sim):
    sim = make_sim([robot([10, 10, 0], name="car", **CAR)])
    car = sim.robots["car"]
    _, radius = circle_of(sim, car, 0.8, 0.8 / 1.5)
    assert radius == pytest.approx(1.5, abs=1e-6)


def test_reverse_turns_the_other_way(make_sim):
    sim = make_sim([robot([10, 10, 0], name="car", **CAR)])
    car = sim.robots["car"]
    car.set_velocity(-0.5, -0.5 / 1.5)  # backwards along a circle of radius 1.5
    sim.run(1.0)
    assert car.pose[0] < 10.0 and car.drive.speed == pytest.approx(-0.5)
    assert car.drive.steering_angle == pytest.approx(math.atan(0.33 / 1.5))


def test_sideways_command_is_refused(make_sim):
    sim = make_sim([robot([10, 10, 0], name="car", **CAR)])
    with pytest.raises(ValueError, match="sideways"):
        sim.robots["car"].set_velocity(0.5, 0.0, vy=0.1)
    assert not sim.robots["car"].overridden


def test_steering_slews_and_speed_ramps(make_sim):
    sim = make_sim([robot([10, 10, 0], name="car", **CAR, max_steer_rate=1.0, max_accel=2.0)])
    car = sim.robots["car"]
    car.set_velocity(2.0, 100.0)
    sim.run(0.25)
    assert car.drive.steering_angle == pytest.approx(0.25, abs=0.02)
    assert car.drive.speed == pytest.approx(0.5, abs=0.04)


def test_stops_at_a_wall_with_its_footprint(make_sim):
    sim = make_sim([robot([2, 2, 0], name="car", **CAR)], size=(4.0, 4.0))
    car = sim.robots["car"]
    car.set_velocity(2.0, 0.0)
    sim.run(3.0)
    front = max(s.bb.right for s in car.shapes)
    assert 4.0 - 0.002 <= front <= 4.0 + 0.01
    assert car.collisions == 1
    assert abs(car.pose[1] - 2.0) < 0.01


def test_pushes_a_crate(make_sim):
    sim = make_sim([robot([1, 2, 0], name="car", **CAR)],
                   [{"type": "box", "center": [2.5, 2.0], "size": [0.4, 0.4], "movable": True,
                     "mass": 1.0}], size=(8.0, 4.0))
    sim.robots["car"].set_velocity(0.5, 0.0)
    sim.run(6.0)
    crate = sim.world.obstacles[0].body.position
    assert crate.x > 3.5
    assert abs(crate.y - 2.0) < 0.05


def test_noise_free_odometry_follows_the_truth(make_sim):
    sim = make_sim([robot([5, 5, 0.3], name="car", **CAR)])
    car = sim.robots["car"]
    car.set_velocity(1.0, 0.4)
    sim.run(5.0)
    assert np.allclose(car.odometry.pose, car.pose, atol=1e-4)


def test_steering_offset_bends_odometry_and_noise_grows_the_covariance(make_sim):
    odometry = {"steer_offset": 0.02, "wheel_noise_std": 0.02, "steer_noise_std": 0.01}
    sim = make_sim([robot([2, 5, 0], name="car", **CAR, odometry=odometry)], seed=3)
    car = sim.robots["car"]
    car.set_velocity(1.0, 0.0)
    sim.run(5.0)
    # 5 m straight, believed steering 0.02 rad left: heading error 5 tan(0.02) / 0.33.
    assert car.pose[2] == pytest.approx(0.0, abs=1e-6)
    assert car.odometry.pose[2] == pytest.approx(5.0 * math.tan(0.02) / 0.33, abs=0.05)
    cov = car.odometry.covariance
    assert cov[2, 2] == pytest.approx(0.01 ** 2 * 5.0 / 0.33 ** 2, rel=0.2)
    assert cov[0, 0] > 0 and cov[1, 1] > cov[0, 0]


def test_footprint_overlapping_an_obstacle_at_the_start_is_bad_input(make_sim):
    # The rear-axle point is 0.3 m clear of the box, but the car's nose reaches into it.
    with pytest.raises(ScenarioError, match=r"robots\[0\].pose: robot starts inside obstacles\[0\]"):
        make_sim([robot([2, 2, 0], name="car", **CAR)],
                 [{"type": "box", "center": [2.6, 2.0], "size": [0.4, 0.4]}])


def test_concave_footprint_is_split_and_centre_of_gravity_is_its_centroid(make_sim):
    l_shape = {"type": "polygon", "points": [[-0.2, -0.2], [0.4, -0.2], [0.4, 0.0], [0.0, 0.0],
                                             [0.0, 0.3], [-0.2, 0.3]]}
    sim = make_sim([robot([3, 3, 0], name="car", **{**CAR, "footprint": l_shape})])
    car = sim.robots["car"]
    assert len(car.shapes) >= 2
    assert sum(s.mass for s in car.shapes) == pytest.approx(5.0)
    assert car.radius == pytest.approx(math.hypot(0.4, 0.2))
