"""What one step of a run looks like, from a live simulation or from a saved .npz run log.

The channel layer (:mod:`.publisher`) reads only these snapshots, so a live run, a recorded
MCAP and a converted log carry the same channels with the same meaning.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

from pymunk_bot.robots.readings import LaserScan
from pymunk_bot.outcomes.runlog import outline_json
from pymunk_bot.viewer.scene import ShapeGeometry, body_pose, world_geometry


@dataclass(frozen=True)
class RobotSnapshot:
    """One robot at one instant; optional parts are None when the robot has no such thing."""

    name: str
    radius: float  # [m]
    pose: np.ndarray  # ground truth [x, y, theta]
    odometry: np.ndarray  # odometry estimate [x, y, theta]
    velocity: tuple[float, ...]  # true (v [m/s], omega [rad/s]) as the robot reports it
    collisions: int  # contact episodes so far
    goal: tuple[float, float] | None  # [m]
    goal_tolerance: float  # [m]
    goal_reached: bool
    command: tuple[float, float] | None = None  # commanded wheel speeds (left, right) [m/s]
    wheel_speeds: tuple[float, float] | None = None  # what the wheels turn at [m/s]
    teleop: bool = False  # commanded by hand, not by the controller
    status: str = ""  # the controller's status ("" without a controller)
    status_message: str = ""  # why, when the controller explains itself
    localizer: np.ndarray | None = None  # the localizer's estimate [x, y, theta]
    lidar_offset: tuple[float, float, float] | None = None  # LiDAR mount in the robot frame
    scan: LaserScan | None = None  # the latest scan taken (at or before this instant)
    path: np.ndarray | None = None  # (N, 2) the controller's planned path [m]
    grid: Any = None  # an OccupancyGrid the robot's mapper is building
    estimate: np.ndarray | None = None  # the localizer's pose, even a passive one [x, y, theta]
    estimate_covariance: np.ndarray | None = None  # its 3x3 covariance of [x, y, theta]
    odometry_covariance: np.ndarray | None = None  # 3x3 covariance of the odometry estimate
    imu: Any = None  # the latest ImuReading (None: no IMU, or no reading yet)
    imu_noise: tuple[float, float] = (0.0, 0.0)  # the IMU's (gyro [rad/s], accel [m/s^2]) std


@dataclass(frozen=True)
class Snapshot:
    """The whole run at one instant."""

    time: float  # simulated [s]
    robots: list[RobotSnapshot]
    obstacle_poses: list[tuple[float, float, float]]  # the movable obstacles, in meta order


@dataclass(frozen=True)
class RunGeometry:
    """What does not change during a run: the arena and the obstacles' shapes."""

    width: float  # arena interior [m]
    height: float  # [m]
    fixed: list[ShapeGeometry]  # walls and fixed obstacles, world frame
    movable: list[tuple[int, list[ShapeGeometry]]]  # (obstacle index, shapes in its body frame)
    meta: dict  # the run-log metadata (pymunk_bot.outcomes.runlog format), for replay


# ---------------------------------------------------------------------------- live simulation


def geometry_of_sim(sim) -> RunGeometry:
    """The static geometry and run-log metadata of a simulation."""
    fixed, movable = world_geometry(sim.world)
    robots = []
    for robot in sim.robots.values():
        lidar = robot.sensor("lidar")
        robots.append({
            "name": robot.name, "radius": float(robot.radius),
            "footprint": outline_json(robot),
            "track_width": getattr(robot.config, "track_width", None),
            "max_wheel_speed": getattr(robot.config, "max_wheel_speed", None),
            "lidar": None if lidar is None else {
                "max_range": float(lidar.config.max_range), "rate": float(lidar.config.rate),
                "offset": [float(v) for v in lidar.config.offset]},
        })
    meta = {
        "format": "pymunk-bot run log", "version": 1, "scenario": sim.config.name,
        "seed": sim.seed, "dt": sim.dt, "width": sim.world.width, "height": sim.world.height,
        "origin": list(sim.world.extent[:2]), "robots": robots, "fixed": [geometry_to_json(g) for g in fixed],
        "movable": [{"obstacle": i, "shapes": [geometry_to_json(g) for g in shapes]}
                    for i, shapes in movable],
    }
    return RunGeometry(sim.world.width, sim.world.height, fixed, movable, meta)


def movable_bodies(sim: Any, geometry: RunGeometry) -> list:
    """The bodies of ``geometry``'s movable obstacles, in its order (``snapshot_of_sim`` reads
    their poses)."""
    return [sim.world.obstacles[i].body for i, _ in geometry.movable]


def snapshot_of_sim(sim, movable_bodies: list) -> Snapshot:
    """The present state of ``sim``; ``movable_bodies`` in the order of its RunGeometry."""
    return Snapshot(float(sim.time), [_robot_of_sim(r) for r in sim.robots.values()],
                    [body_pose(b) for b in movable_bodies])


def _robot_of_sim(robot) -> RobotSnapshot:
    controller = robot.controller
    path = controller.debug_path() if controller is not None else None
    localizer = getattr(robot, "localizer", None)
    if getattr(localizer, "passive", False):
        localizer = None  # ground truth or odometry: already on their own topics
    mapper = getattr(robot, "mapper", None)
    drive = getattr(robot, "drive", None)  # the diff drive's wheel state, when there is one
    lidar, imu, belief = robot.sensor("lidar"), robot.sensor("imu"), robot.localizer
    return RobotSnapshot(
        name=robot.name, radius=float(robot.radius),
        pose=np.array(robot.pose, dtype=float), odometry=np.array(robot.odometry.pose, dtype=float),
        velocity=tuple(float(v) for v in robot.velocity), collisions=int(robot.collisions),
        goal=None if robot.goal is None else (float(robot.goal[0]), float(robot.goal[1])),
        goal_tolerance=float(robot.goal_tolerance), goal_reached=bool(robot.goal_reached),
        command=_pair(getattr(drive, "target", None)),
        wheel_speeds=_pair(getattr(drive, "wheel_speeds", None)),
        teleop=bool(getattr(robot, "overridden", False)),
        status="" if controller is None else str(controller.status),
        status_message="" if controller is None else str(getattr(controller, "message", "") or ""),
        localizer=None if localizer is None else np.array(localizer.pose, dtype=float),
        lidar_offset=None if lidar is None else _triple(lidar.config.offset),
        scan=None if lidar is None else lidar.latest,
        path=None if not path else np.asarray(path, dtype=float).reshape(-1, 2),
        grid=None if mapper is None else getattr(mapper, "grid", None),
        estimate=None if belief is None else np.array(belief.pose, dtype=float),
        estimate_covariance=_covariance(belief),
        odometry_covariance=_covariance(robot.odometry),
        imu=None if imu is None else imu.reading,
        imu_noise=(0.0, 0.0) if imu is None else (float(imu.config.gyro_noise_std),
                                                  float(imu.config.accel_noise_std)))


def _covariance(estimator) -> np.ndarray | None:
    """A copy of an estimator's 3x3 covariance, if it keeps one."""
    covariance = getattr(estimator, "covariance", None)
    return None if covariance is None else np.array(covariance, dtype=float).reshape(3, 3)


def _pair(value) -> tuple[float, float] | None:
    if value is None:
        return None
    a, b = value
    return float(a), float(b)


def _triple(value) -> tuple[float, float, float]:
    a, b, c = value
    return float(a), float(b), float(c)


# ---------------------------------------------------------------------------- .npz run log


def geometry_of_log(log) -> RunGeometry:
    """The static geometry of a :class:`~pymunk_bot.outcomes.runlog.RunLog`."""
    movable = [(int(m["obstacle"]), shapes)
               for m, shapes in zip(log.meta["movable"], log.movable_shapes())]
    width, height = log.size
    meta = json.loads(json.dumps(log.meta))  # a deep copy, completed with the LiDAR mounts
    for robot in meta["robots"]:
        if robot.get("lidar") is not None:
            robot["lidar"]["offset"] = list(_log_offset(log, robot["name"]))
    return RunGeometry(width, height, log.fixed_shapes(), movable, meta)


def snapshots_of_log(log) -> Iterator[Snapshot]:
    """One snapshot per logged step; each robot's scan is the latest taken by then."""
    robots = log.meta["robots"]
    for i, t in enumerate(log.time):
        states = []
        for j, meta in enumerate(robots):
            goal = log.goal[i, j]
            lidar = meta.get("lidar")
            states.append(RobotSnapshot(
                name=meta["name"], radius=float(meta["radius"]), pose=log.pose[i, j],
                odometry=log.odometry[i, j], velocity=tuple(float(v) for v in log.velocity[i, j]),
                collisions=int(log.collisions[i, j]),
                goal=None if np.isnan(goal).any() else (float(goal[0]), float(goal[1])),
                goal_tolerance=float(log.goal_tolerance[i, j]),
                goal_reached=bool(log.goal_reached[i, j]),
                command=_pair(log.command[i, j]), wheel_speeds=_pair(log.wheel_speeds[i, j]),
                teleop=bool(log.teleop[i, j]),
                lidar_offset=None if lidar is None else _log_offset(log, meta["name"]),
                scan=_log_scan(log, meta["name"], float(t))))
        poses = [_triple(p) for p in log.obstacle_pose[i]]
        yield Snapshot(float(t), states, poses)


def _log_offset(log, name: str) -> tuple[float, float, float]:
    scans = log.scans.get(name)
    if scans is None or len(scans.offset) != 3:
        return 0.0, 0.0, 0.0
    return _triple(scans.offset)


def _log_scan(log, name: str, t: float) -> LaserScan | None:
    scans = log.scans.get(name)
    if scans is None or not len(scans.time):
        return None
    k = int(np.searchsorted(scans.time, t + 1e-9, side="right")) - 1
    if k < 0:
        return None
    return LaserScan(ranges=scans.ranges[k], angles=scans.angles, min_range=0.0,
                     max_range=scans.max_range, offset=_triple(scans.offset),
                     time=float(scans.time[k]))


# ---------------------------------------------------------------------------- geometry JSON


def geometry_to_json(g: ShapeGeometry) -> dict:
    """A shape in the run log's JSON form (see docs/viewer.md)."""
    return {"kind": g.kind, "points": np.asarray(g.points).tolist(), "radius": float(g.radius),
            "wall": bool(g.wall), "group": int(g.group)}
