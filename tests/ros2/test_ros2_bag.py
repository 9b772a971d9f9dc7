"""`run --log run.mcap --profile ros2`: every topic, decoded by rosbags (an independent MCAP
reader and CDR deserializer), holds what the simulation had at that instant, bit for bit."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot, scenario

from pymunk_bot import Simulation
from pymunk_bot.cli import main
from pymunk_bot.foxglove.frames import yaw_quaternion
from pymunk_bot.foxglove.snapshot import snapshot_of_sim
from pymunk_bot.ros2.bag import Ros2BagLogger, write_bag
from pymunk_bot.ros2.messages import compose, correction
from pymunk_bot.ros2.worldmap import world_grid

from ros2_helpers import read_bag

NS = 1_000_000_000


def make_sim(seed: int = 3) -> Simulation:
    """One robot with a noisy LiDAR that sees nothing to one side, an IMU, drifting odometry,
    an EKF, a plan to a goal and a crate to push."""
    return Simulation.from_dict(scenario(
        [robot([1.0, 1.5, 0.3], name="r1",
               lidar={"beams": 90, "max_range": 3.0, "rate": 10.0, "noise_std": 0.01,
                      "offset": [0.1, 0.0, 0.2]},
               imu={"gyro_noise_std": 0.01, "accel_noise_std": 0.05},
               odometry={"wheel_noise_std": 0.01, "left_scale_error": 0.02},
               localization={"type": "ekf"},
               controller={"type": "navigate"}, goal={"position": [6.0, 2.0], "tolerance": 0.2})],
        obstacles=[{"type": "box", "center": [3.5, 1.0], "size": [0.4, 0.4], "movable": True,
                    "mass": 2.0},
                   {"type": "circle", "center": [4.0, 3.2], "radius": 0.3}],
        size=(12.0, 4.0), dt=1 / 50), seed=seed)


class Recorder:
    """What the simulation held after each step (an observer beside the bag writer)."""

    def __init__(self) -> None:
        self.steps: list = []

    def __call__(self, sim) -> None:
        self.steps.append(snapshot_of_sim(sim, []))


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    sim = make_sim()
    path = tmp_path_factory.mktemp("bag") / "run.mcap"
    grid = world_grid(sim.config)
    recorder = Recorder()
    recorder(sim)
    logger = Ros2BagLogger(path, grid).attach(sim)
    sim.observers.append(recorder)
    sim.run(2.0)
    logger.save()
    return read_bag(path), recorder.steps, grid


def test_metadata_lists_types_and_latched_qos(recorded):
    bag, _, _ = recorded
    expected = {"/scan": "sensor_msgs/msg/LaserScan", "/odom": "nav_msgs/msg/Odometry",
                "/ground_truth": "nav_msgs/msg/Odometry", "/tf": "tf2_msgs/msg/TFMessage",
                "/tf_static": "tf2_msgs/msg/TFMessage", "/map": "nav_msgs/msg/OccupancyGrid",
                "/clock": "rosgraph_msgs/msg/Clock", "/imu": "sensor_msgs/msg/Imu",
                "/pose": "geometry_msgs/msg/PoseWithCovarianceStamped",
                "/plan": "nav_msgs/msg/Path", "/obstacles": "visualization_msgs/msg/MarkerArray"}
    assert {t: bag.types[t] for t in expected} == expected
    for topic in ("/map", "/tf_static"):
        assert bag.durability[topic] == "TRANSIENT_LOCAL"
        assert len(bag.messages[topic]) == 1
    assert bag.durability["/scan"] == "VOLATILE"
    assert bag.profile == "ros2"


def test_clock_odometry_and_ground_truth_are_the_simulation(recorded):
    bag, steps, _ = recorded
    clock = bag.messages["/clock"]
    assert len(clock) == len(steps)
    for (log_time, msg), snap in zip(clock, steps):
        assert log_time == round(snap.time * NS)
        assert msg.clock.sec * NS + msg.clock.nanosec == log_time
    for (_, odom), (_, truth), snap in zip(bag.messages["/odom"], bag.messages["/ground_truth"],
                                           steps):
        r = snap.robots[0]
        assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
        assert (truth.header.frame_id, truth.child_frame_id) == ("map", "base_link")
        for msg, pose in ((odom, r.odometry), (truth, r.pose)):
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            assert (p.x, p.y, p.z) == (pose[0], pose[1], 0.0)  # float64, bit for bit
            assert (q.x, q.y, q.z, q.w) == yaw_quaternion(pose[2])
        cov = odom.pose.covariance.reshape(6, 6)
        assert np.array_equal(cov[np.ix_([0, 1, 5], [0, 1, 5])], r.odometry_covariance)
        assert truth.twist.twist.linear.x == r.velocity[0]
        assert truth.twist.twist.angular.z == r.velocity[-1]
    assert steps[-1].robots[0].odometry_covariance[0, 0] > 0  # the noise model did propagate


def test_tf_chain_puts_the_robot_where_its_localizer_believes(recorded):
    bag, steps, _ = recorded
    for (_, tf), snap in zip(bag.messages["/tf"], steps):
        r = snap.robots[0]
        by_child = {t.child_frame_id: t for t in tf.transforms}
        assert by_child["odom"].header.frame_id == "map"
        assert by_child["base_link"].header.frame_id == "odom"
        assert by_child["odom"].header.stamp.sec * NS + by_child["odom"].header.stamp.nanosec \
            == round(snap.time * NS)
        expected = {"odom": correction(r.estimate, r.odometry), "base_link": r.odometry}
        for child, pose in expected.items():
            t = by_child[child].transform
            assert (t.translation.x, t.translation.y) == (pose[0], pose[1])
            assert (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w) \
                == yaw_quaternion(pose[2])
        # map -> odom -> base_link lands on the localizer's estimate
        x, y, theta = compose(expected["odom"], r.odometry)
        assert np.allclose([x, y], r.estimate[:2], atol=1e-9)
        assert abs(math.remainder(theta - r.estimate[2], 2 * math.pi)) < 1e-9
    (_, static), = bag.messages["/tf_static"]
    mount = static.transforms[0]
    assert (mount.header.frame_id, mount.child_frame_id) == ("base_link", "laser")
    assert (mount.transform.translation.x, mount.transform.rotation.z) == (
        0.1, yaw_quaternion(0.2)[2])


def test_scans_are_the_lidar_readings_with_inf_for_no_return(recorded):
    bag, steps, _ = recorded
    taken = {}
    for snap in steps:
        scan = snap.robots[0].scan
        if scan is not None:
            taken[round(scan.time * NS)] = scan
    scans = bag.messages["/scan"]
    assert [t for t, _ in scans] == sorted(taken)  # one message per scan, at its time
    assert len(scans) == 21  # 2 s at 10 Hz, and the scan at t = 0
    saw_inf = False
    for log_time, msg in scans:
        scan = taken[log_time]
        assert msg.header.frame_id == "laser"
        assert msg.header.stamp.sec * NS + msg.header.stamp.nanosec == log_time
        expected = np.asarray(scan.ranges, dtype=np.float32).copy()
        no_return = expected >= np.float32(3.0)
        expected[no_return] = np.inf
        assert np.array_equal(msg.ranges, expected)
        saw_inf |= bool(no_return.any()) and bool(np.isposinf(msg.ranges).any())
        assert msg.range_max == np.float32(3.0)
        # beam k points at angle_min + k * increment in the laser frame (mount yaw removed)
        beams = msg.angle_min + np.arange(len(msg.ranges)) * msg.angle_increment
        assert np.allclose(beams + 0.2, scan.angles, atol=1e-5)
    assert saw_inf


def test_imu_pose_plan_map_and_markers(recorded):
    bag, steps, grid = recorded
    (_, occupancy), = bag.messages["/map"]
    assert (occupancy.info.width, occupancy.info.height) == (grid.cols, grid.rows)
    assert np.array_equal(occupancy.data.reshape(grid.rows, grid.cols), grid.data)
    assert occupancy.info.origin.position.x == grid.origin[0]
    final = steps[-1].robots[0]
    _, imu = bag.messages["/imu"][-1]
    assert imu.angular_velocity.z == final.imu.yaw_rate
    assert (imu.linear_acceleration.x, imu.linear_acceleration.y) == final.imu.accel
    assert imu.orientation_covariance[0] == -1.0
    _, pose = bag.messages["/pose"][-1]
    assert (pose.pose.pose.position.x, pose.pose.pose.position.y) == tuple(final.localizer[:2])
    _, plan = bag.messages["/plan"][-1]
    xy = np.array([(p.pose.position.x, p.pose.position.y) for p in plan.poses])
    assert len(xy) >= 2 and np.array_equal(xy, final.path)
    _, markers = bag.messages["/obstacles"][0]
    assert markers.markers[0].type == 4 and markers.markers[0].header.frame_id == "map"


def test_cli_writes_a_bag_and_convert_makes_one_from_npz_and_foxglove_mcap(tmp_path, capsys):
    scenario_path = tmp_path / "s.yaml"
    import yaml

    scenario_path.write_text(yaml.safe_dump(make_sim().config.model_dump(mode="json")))
    bag = tmp_path / "run.mcap"
    npz = tmp_path / "run.npz"
    args = [str(scenario_path), "--headless", "--duration", "1", "--seed", "3"]
    assert main(["run", *args, "--log", str(bag), "--profile", "ros2"]) in (0, 1)
    assert main(["run", *args, "--log", str(npz)]) in (0, 1)
    direct = read_bag(bag)
    assert direct.types["/map"] == "nav_msgs/msg/OccupancyGrid"
    converted = tmp_path / "converted.mcap"
    assert main(["convert", str(npz), str(converted), "--profile", "ros2"]) == 0
    from_npz = read_bag(converted)
    # the same run, logged two ways: the same scans and ground truth
    assert [t for t, _ in from_npz.messages["/scan"]] == [t for t, _ in direct.messages["/scan"]]
    for (_, a), (_, b) in zip(from_npz.messages["/scan"], direct.messages["/scan"]):
        assert np.array_equal(a.ranges, b.ranges)
    truth = [m.pose.pose.position.x for _, m in direct.messages["/ground_truth"]]
    assert [m.pose.pose.position.x for _, m in from_npz.messages["/ground_truth"]] == truth
    fox = tmp_path / "fox.mcap"
    assert main(["convert", str(npz), str(fox)]) == 0
    again = tmp_path / "again.mcap"
    assert main(["convert", str(fox), str(again), "--profile", "ros2"]) == 0
    assert len(read_bag(again).messages["/scan"]) == len(direct.messages["/scan"])


def test_bad_options_are_one_line_and_leave_nothing(tmp_path, capsys):
    target = tmp_path / "out.mcap"
    assert main(["run", "--headless", "--duration", "0.1", "--log", str(tmp_path / "a.npz"),
                 "--profile", "ros2"]) == 2
    assert "--profile: only applies with --log RUN.mcap" in capsys.readouterr().err
    assert main(["convert", str(tmp_path / "missing.npz"), str(target), "--profile", "ros2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "missing.npz" in err
    assert not list(tmp_path.iterdir())


def test_write_bag_aborts_cleanly(tmp_path):
    class Broken:
        meta = {"robots": []}

    with pytest.raises(Exception):
        write_bag(Broken(), tmp_path / "x.mcap")
    assert not list(tmp_path.iterdir())


def test_a_converted_log_gets_the_map_of_its_fixed_shapes(tmp_path):
    """/map from the shapes an .npz keeps matches /map from the scenario (cell for cell but
    along the shapes' edges, where the two rasterisations may round differently)."""
    from pymunk_bot.outcomes.runlog import RunLogger

    sim = make_sim()
    logger = RunLogger().attach(sim)
    sim.run(0.2)
    npz = tmp_path / "run.npz"
    logger.save(npz)
    from pymunk_bot.outcomes.runlog import load_log

    write_bag(load_log(npz), tmp_path / "c.mcap")
    (_, converted), = read_bag(tmp_path / "c.mcap").messages["/map"]
    grid = world_grid(sim.config)
    assert (converted.info.width, converted.info.height) == (grid.cols, grid.rows)
    data = converted.data.reshape(grid.rows, grid.cols)
    assert np.mean(data == grid.data) > 0.99
    row, col = grid.cell_of(np.array([4.0, 3.2]))  # the pillar's centre
    assert data[row, col] == 100 and grid.data[row, col] == 100
    row, col = grid.cell_of(np.array([2.0, 2.0]))  # open floor
    assert data[row, col] == 0


def test_several_robots_share_map_and_tf_with_prefixed_frames(tmp_path):
    sim = Simulation.from_dict(scenario(
        [robot([1.0 + 2.0 * k, 1.5, 0.0], name=f"r{k + 1}", lidar={"beams": 20, "rate": 5.0})
         for k in range(2)], size=(6.0, 3.0)))
    logger = Ros2BagLogger(tmp_path / "two.mcap", world_grid(sim.config)).attach(sim)
    sim.run(0.5)
    sim.reset()  # the bag goes on: the clock starts again, /tf_static and /map are sent again
    sim.run(0.2)
    logger.save()
    bag = read_bag(tmp_path / "two.mcap")
    assert {"/r1/scan", "/r2/scan", "/r1/odom", "/r2/ground_truth", "/tf", "/map"} <= set(bag.types)
    assert "/scan" not in bag.types
    _, tf = bag.messages["/tf"][0]
    assert {(t.header.frame_id, t.child_frame_id) for t in tf.transforms} == {
        ("map", "r1/odom"), ("r1/odom", "r1/base_link"), ("map", "r2/odom"),
        ("r2/odom", "r2/base_link")}
    _, static = bag.messages["/tf_static"][0]
    assert {t.child_frame_id for t in static.transforms} == {"r1/laser", "r2/laser"}
    assert len(bag.messages["/tf_static"]) == len(bag.messages["/map"]) == 2
    clock = [t for t, _ in bag.messages["/clock"]]
    assert clock.count(0) == 2 and len(clock) == 2 + round(0.7 * 60)


def test_a_mapping_robot_s_map_is_latched_on_slam_map(tmp_path):
    sim = Simulation.from_dict(scenario(
        [robot([1.0, 1.5, 0.0], name="r1", lidar={"beams": 90, "max_range": 4.0, "rate": 10.0},
               mapping={"resolution": 0.1}, controller={"type": "wheels", "left": 0.2,
                                                        "right": 0.3})],
        obstacles=[{"type": "box", "center": [3.0, 1.5], "size": [0.4, 0.4]}], size=(6.0, 3.0)))
    grids = []
    logger = Ros2BagLogger(tmp_path / "m.mcap").attach(sim)
    sim.observers.append(lambda s: grids.append((s.time, s.robots["r1"].mapper.grid)))
    sim.run(2.5)
    logger.save()
    bag = read_bag(tmp_path / "m.mcap")
    assert bag.types["/slam_map"] == "nav_msgs/msg/OccupancyGrid"
    assert bag.durability["/slam_map"] == "TRANSIENT_LOCAL"
    maps = bag.messages["/slam_map"]
    assert 2 <= len(maps) <= 4  # at most once a simulated second
    by_time = {round(t * NS): g for t, g in grids}
    for log_time, msg in maps[1:]:
        grid = by_time[log_time]
        assert np.array_equal(msg.data.reshape(grid.rows, grid.cols), grid.data)
        assert msg.info.resolution == pytest.approx(0.1)
    final = maps[-1][1].data
    assert (final >= 65).any() and ((final >= 0) & (final < 20)).any()  # walls seen, floor free
