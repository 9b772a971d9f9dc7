"""EKF localization (accuracy, consistency) and SLAM (trajectory, map, loop closures, speed)."""
import time

import numpy as np
import pytest

import harness
from pymunk_bot.localization import (EkfConfig, EkfLocalizer, SlamConfig, SlamLocalizer,
                                     check_localizer)
from pymunk_bot.localization.metrics import ate, map_scores
from pymunk_bot.localization.posegraph import Edge, optimize
from pymunk_bot.localization.se2 import between, compose, wrap
from pymunk_bot.maps.rasterize import scenario_grid


def _nees_recorder(values):
    def on_step(sim, loc):
        robot = sim.robots["r1"]
        scan = robot.lidar.latest
        if abs(scan.time - sim.time) < 1e-9:  # after each measurement update
            e = loc.pose - robot.pose
            e[2] = wrap(e[2])
            values.append(float(e @ np.linalg.solve(loc.covariance, e)))
    return on_step


def test_ekf_is_accurate_and_consistent_on_a_map_that_matches_the_world():
    from scipy.stats import chi2  # here: scipy.stats costs every test worker 0.4 s

    nees = []
    trial, loc, _ = harness.run(harness.ros_map(seed=2), lambda ctx: EkfLocalizer(EkfConfig(), ctx),
                                30.0, seed=2, on_step=_nees_recorder(nees))
    assert trial.errors()["rmse"] <= 0.05
    nees = np.array(nees)
    inside = np.mean((nees >= chi2.ppf(0.025, 3)) & (nees <= chi2.ppf(0.975, 3)))
    assert inside >= 0.9, f"NEES inside the 95 % band for only {inside:.0%} of {nees.size} updates"
    assert loc.updates >= 250


def test_ekf_tracks_the_office_within_5_cm():
    trial, _, _ = harness.run(harness.office(seed=5), lambda ctx: EkfLocalizer(EkfConfig(), ctx), 20.0)
    assert trial.errors()["rmse"] <= 0.05
    assert trial.errors()["heading_rmse"] <= np.deg2rad(2.0)


LOOP = [(4.0, 1.0), (4.0, 3.6), (1.0, 3.6), (1.0, 1.5), (1.4, 1.0), (4.5, 1.0)]


def test_slam_closes_a_loop_with_centimetre_error_and_maps_the_room():
    sim, _, _ = harness.office(seed=0)
    cpu = time.process_time()  # CPU time: what the run costs, whatever the machine's load
    trial, loc, sim = harness.run((sim, None, LOOP), lambda ctx: SlamLocalizer(SlamConfig(), ctx), 40.0)
    _, truth, estimate = trial.arrays()
    assert ate(truth, estimate)["rmse"] <= 0.05
    assert loc.loop_closures, "driving the loop again must close it"
    scores = map_scores(loc.grid, scenario_grid(sim.config, 0.05))
    assert scores["precision"] >= 0.95
    assert time.process_time() - cpu < trial.sim_time  # faster than real time
    assert loc.grid.data.min() == -1 and loc.grid.data.max() >= 65


def test_pose_graph_loop_closure_pulls_a_drifting_square_back():
    truth = np.array([[0, 0, 0], [2, 0, np.pi / 2], [2, 2, np.pi], [0, 2, -np.pi / 2], [0, 0, 0]], float)
    drift = np.array([0.0, 0.0, 0.05])  # odometry turns 0.05 rad too far each leg
    odometry = [truth[0]]
    for i in range(4):
        odometry.append(compose(odometry[-1], compose(between(truth[i], truth[i + 1]), drift)))
    odometry = np.array(odometry)
    info = np.diag([100.0, 100.0, 400.0])
    edges = [Edge(i, i + 1, between(odometry[i], odometry[i + 1]), info) for i in range(4)]
    edges.append(Edge(0, 4, np.zeros(3), info * 100))  # a loop closure: back at the start
    solved, _ = optimize(odometry, edges)
    before = np.hypot(*(odometry[:, :2] - truth[:, :2]).T).max()
    after = np.hypot(*(solved[:, :2] - truth[:, :2]).T).max()
    assert after < 0.35 * before
    np.testing.assert_allclose(solved[0], truth[0], atol=1e-6)  # the first node stays put


def test_localizers_that_match_scans_refuse_a_robot_without_lidar():
    sim, _, _ = harness.office()
    robot = sim.config.robots[0].model_copy(update={"lidar": None})
    with pytest.raises(ValueError, match="ekf needs a LiDAR"):
        check_localizer(EkfConfig(), robot)
    with pytest.raises(ValueError, match="mcl needs a map"):
        from pymunk_bot.localization import MclConfig
        check_localizer(MclConfig(), sim.config.robots[0], has_map=False)
    few = sim.config.robots[0].lidar.model_copy(update={"beams": 4})
    with pytest.raises(ValueError, match="at least 10 beams"):
        check_localizer(SlamConfig(), sim.config.robots[0].model_copy(update={"lidar": few}))
    check_localizer(SlamConfig(), sim.config.robots[0], has_map=False)  # slam needs no map
