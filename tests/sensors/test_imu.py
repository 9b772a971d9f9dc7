"""IMU: yaw rate and robot-frame acceleration, ground truth without noise, then noise and bias."""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest
from builders import robot, wheels

from pymunk_bot.config.schema import ImuConfig
from pymunk_bot.geometry.arcs import sinc_half
from pymunk_bot.sensors.imu import Imu, ImuReading

TRACK = 0.3  # [m]


def test_reads_ground_truth_yaw_rate_and_no_acceleration_in_a_spin(make_sim):
    sim = make_sim([robot([5, 5, 0.4], imu={}, controller=wheels(-0.45, 0.45))])
    r = sim.robots["r"]
    sim.run(1.0)  # past the ramp
    for _ in range(30):
        sim.step()
        assert r.imu.yaw_rate == r.body.angular_velocity
        assert r.imu.yaw_rate == pytest.approx(0.9 / TRACK)
        assert r.imu.accel == pytest.approx((0.0, 0.0), abs=1e-6)


@pytest.mark.parametrize("heading,substeps,rate", [(0.0, 1, None), (2.0, 4, None), (-1.0, 2, 5.0)])
def test_an_arc_has_centripetal_acceleration_to_the_left(make_sim, heading, substeps, rate):
    left, right = 0.4, 0.6
    v, omega = (left + right) / 2, (right - left) / TRACK
    sim = make_sim([robot([10, 10, heading], imu={"rate": rate}, controller=wheels(left, right))],
                   substeps=substeps)
    r = sim.robots["r"]
    sim.run(1.0)
    for _ in range(30):
        sim.step()
        forward, lateral = r.imu.accel
        assert forward == pytest.approx(0.0, abs=1e-6)
        # Toward the centre of the turn: the mean over the period T, shorter than v * omega by
        # sinc(omega T / 2) (7e-4 at 5 Hz).
        period = 1.0 / (rate or 60.0)
        assert lateral == pytest.approx(v * omega * sinc_half(omega * period), rel=2e-5)
        assert r.imu.yaw_rate == pytest.approx(omega, rel=1e-9)


def test_reads_the_acceleration_ramp(make_sim):
    sim = make_sim([robot([2, 10, -0.7], imu={}, max_accel=2.0, controller=wheels(1.0, 1.0))])
    r = sim.robots["r"]
    assert r.imu.reading == ImuReading(time=0.0, yaw_rate=0.0, accel=(0.0, 0.0))  # at rest at t = 0
    sim.run(0.25)
    assert r.imu.accel == pytest.approx((2.0, 0.0), abs=1e-6)  # speeding up at max_accel
    sim.run(0.5)
    assert r.imu.accel == pytest.approx((0.0, 0.0), abs=1e-6)  # cruising at 1 m/s
    r.set_wheel_speeds(0.0, 0.0)
    sim.run(0.25)
    assert r.imu.accel == pytest.approx((-2.0, 0.0), abs=1e-6)  # braking


def test_rate_and_acceleration_averaged_over_the_period(make_sim):
    # 0.75 m/s at 2 m/s^2: the speed changes during the first 0.375 s only.
    sim = make_sim([robot([2, 10, 0.0], imu={"rate": 2.0}, max_accel=2.0,
                          controller=wheels(0.75, 0.75))])
    r = sim.robots["r"]
    times = [r.imu.reading.time]
    for _ in range(90):
        sim.step()
        if r.imu.reading.time != times[-1]:
            times.append(r.imu.reading.time)
        if sim.steps == 30:
            # Speed 0 -> 0.75 m/s within the first 0.5 s period: mean acceleration 1.5 m/s^2.
            assert r.imu.accel[0] == pytest.approx(0.75 / 0.5, abs=1e-6)
    assert times == pytest.approx([0.0, 0.5, 1.0, 1.5])
    assert r.imu.accel == pytest.approx((0.0, 0.0), abs=1e-6)


def test_noise_and_constant_bias_have_the_configured_statistics(make_sim):
    imu = {"gyro_noise_std": 0.02, "gyro_bias": 0.005, "accel_noise_std": 0.1,
           "accel_bias": [0.3, -0.2]}
    sim = make_sim([robot([5, 5, 0.0], imu=imu)])
    r = sim.robots["r"]
    gyro, accel = [], []
    for _ in range(4000):
        sim.step()
        gyro.append(r.imu.yaw_rate)
        accel.append(r.imu.accel)
    gyro, accel = np.array(gyro), np.array(accel)
    n = len(gyro)
    assert gyro.mean() == pytest.approx(0.005, abs=4 * 0.02 / math.sqrt(n))
    assert gyro.std() == pytest.approx(0.02, rel=0.05)
    assert accel.mean(axis=0) == pytest.approx([0.3, -0.2], abs=4 * 0.1 / math.sqrt(n))
    assert accel.std(axis=0) == pytest.approx([0.1, 0.1], rel=0.05)
    assert abs(np.corrcoef(accel.T)[0, 1]) < 0.06  # independent axes


def test_bias_random_walk_spreads_with_the_square_root_of_time():
    walk_gyro, walk_accel, rate, duration, runs = 0.01, 0.02, 4.0, 25.0, 1500
    config = ImuConfig(rate=rate, gyro_bias_walk=walk_gyro, accel_bias_walk=walk_accel)
    body = pymunk.Body(1.0, 1.0)  # at rest: every reading is bias only
    ends = []
    for rng in np.random.default_rng(21).spawn(runs):
        imu = Imu(config, body, rng)
        for k in range(int(duration * rate) + 1):
            imu.update(k / rate)
        ends.append((imu.yaw_rate, *imu.accel))
    ends = np.array(ends)
    expected = np.array([walk_gyro, walk_accel, walk_accel]) * math.sqrt(duration)
    assert ends.std(axis=0) == pytest.approx(expected, rel=0.06)  # 1500 runs: ~2 % per std
    assert np.all(np.abs(ends.mean(axis=0)) < 4 * expected / math.sqrt(runs))


def test_imu_noise_is_seeded(make_sim):
    def readings(seed):
        sim = make_sim([robot([5, 5, 0.0], imu={"gyro_noise_std": 0.1, "accel_noise_std": 0.1},
                              controller=wheels(0.2, 0.3))], seed=seed)
        out = []
        for _ in range(20):
            sim.step()
            out.append((sim.robots["r"].imu.yaw_rate, *sim.robots["r"].imu.accel))
        return np.array(out)

    assert np.array_equal(readings(3), readings(3))
    assert not np.allclose(readings(3), readings(4))


def test_controllers_see_the_imu_reading(make_sim):
    sim = make_sim([robot([5, 5, 0.0], imu={}, controller=wheels(0.2, 0.4))])
    r = sim.robots["r"]
    sim.run(0.5)
    reading = sim.observe(r).extra["imu"]
    assert reading is r.imu.reading and reading.time == pytest.approx(0.5)
