"""Snapshots of a run -> standard ROS 2 messages (``rosbags`` types, Humble definitions).

:class:`RosMessages` reads the same :class:`~pymunk_bot.foxglove.snapshot.Snapshot` s as the
Foxglove publisher and yields :class:`Outgoing` messages stamped with simulated time. What is
sent when (docs/ros2.md): ``/clock``, ``/tf`` and every robot's odometry and ground truth every
step; a scan or an IMU reading when a new one was taken; a plan or the obstacles' markers when
they change (and every ``REFRESH_PERIOD``); ``/tf_static`` and ``/map`` once, latched.
Conversions follow ROS conventions: REP-103 units and axes, REP-105 frames, REP-117 ``+inf``
for a beam with no return.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from pymunk_bot.foxglove.frames import nanoseconds, yaw_quaternion
from pymunk_bot.foxglove.publisher import heading_along
from pymunk_bot.foxglove.snapshot import (RobotSnapshot, RunGeometry, Snapshot, geometry_of_sim,
                                 movable_bodies, snapshot_of_sim)
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.ros2.names import (CLOCK_TOPIC, MAP_FRAME, MAP_TOPIC, OBSTACLES_TOPIC, TF_STATIC_TOPIC, TF_TOPIC,
                    TYPES, RobotNames, robot_names)

REFRESH_PERIOD = 1.0  # [s] simulated: plans and markers again, for late subscribers
GRID_PERIOD = 1.0  # [s] simulated: at most this often a robot's built map, when it changed
MOVED = 1e-6  # [m] or [rad]: an obstacle that moved less keeps its marker
MARKER_HEIGHT = 0.5  # [m] drawn height of obstacles in RViz (the world is flat)


@functools.cache
def typestore() -> Any:
    """The ROS 2 Humble message types (rosbags' built-in store of the standard packages)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def msg_class(msgtype: str) -> Any:
    """The rosbags class of ``msgtype`` (e.g. "sensor_msgs/msg/LaserScan")."""
    return typestore().types[msgtype]


@dataclass(frozen=True)
class Outgoing:
    """One message to publish: on ``topic``, of ``msgtype``, at simulated ``log_time`` [ns]."""

    topic: str
    msgtype: str
    msg: Any
    log_time: int


# ---------------------------------------------------------------------------- small messages


def stamp(t: float) -> Any:
    """builtin_interfaces/msg/Time of simulated time ``t`` [s]."""
    sec, nanosec = divmod(nanoseconds(t), 1_000_000_000)
    return msg_class("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec)


def header(t: float, frame: str) -> Any:
    return msg_class("std_msgs/msg/Header")(stamp=stamp(t), frame_id=frame)


def _quaternion(theta: float) -> Any:
    x, y, z, w = yaw_quaternion(theta)
    return msg_class("geometry_msgs/msg/Quaternion")(x=x, y=y, z=z, w=w)


def pose_msg(x: float, y: float, theta: float) -> Any:
    """geometry_msgs/msg/Pose of a planar pose [m, m, rad]."""
    return msg_class("geometry_msgs/msg/Pose")(
        position=msg_class("geometry_msgs/msg/Point")(x=float(x), y=float(y), z=0.0),
        orientation=_quaternion(float(theta)))


def _vector(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
    return msg_class("geometry_msgs/msg/Vector3")(x=float(x), y=float(y), z=float(z))


def _transform(t: float, parent: str, child: str, pose) -> Any:
    x, y, theta = (float(v) for v in pose)
    return msg_class("geometry_msgs/msg/TransformStamped")(
        header=header(t, parent), child_frame_id=child,
        transform=msg_class("geometry_msgs/msg/Transform")(translation=_vector(x, y),
                                                           rotation=_quaternion(theta)))


def covariance6(covariance3: np.ndarray | None) -> np.ndarray:
    """A planar (x, y, theta) 3x3 covariance as ROS's row-major 6x6 (x, y, z, roll, pitch, yaw)."""
    out = np.zeros((6, 6))
    if covariance3 is not None:
        index = np.array([0, 1, 5])
        out[np.ix_(index, index)] = covariance3
    return out.reshape(36)


def compose(a, b) -> tuple[float, float, float]:
    """Planar pose ``a`` followed by ``b`` (b expressed in a's frame)."""
    ax, ay, at = (float(v) for v in a)
    bx, by, bt = (float(v) for v in b)
    c, s = math.cos(at), math.sin(at)
    return ax + c * bx - s * by, ay + s * bx + c * by, at + bt


def inverse(a) -> tuple[float, float, float]:
    """The planar pose that undoes ``a``."""
    x, y, theta = (float(v) for v in a)
    c, s = math.cos(theta), math.sin(theta)
    return -c * x - s * y, s * x - c * y, -theta


def correction(estimate, odometry) -> tuple[float, float, float]:
    """``map`` -> ``odom``: the transform that puts the odometry pose on the estimate."""
    return compose(estimate, inverse(odometry))


def laser_scan(scan, frame: str, rate: float) -> Any:
    """sensor_msgs/msg/LaserScan of one scan, in its mount frame (our beam angles include the
    mount's yaw; ROS's do not). A beam with no return reads max_range here and ``+inf`` there
    (REP-117)."""
    angles = np.asarray(scan.angles, dtype=float)
    yaw = float(scan.offset[2]) if len(scan.offset) == 3 else 0.0
    ranges = np.array(scan.ranges, dtype=np.float32)
    ranges[ranges >= np.float32(scan.max_range)] = np.inf
    step = float(angles[-1] - angles[0]) / (len(angles) - 1) if len(angles) > 1 else 0.0
    return msg_class(TYPES["scan"])(
        header=header(scan.time, frame), angle_min=float(angles[0]) - yaw,
        angle_max=float(angles[-1]) - yaw, angle_increment=step, time_increment=0.0,
        scan_time=1.0 / rate if rate > 0 else 0.0, range_min=float(scan.min_range),
        range_max=float(scan.max_range), ranges=ranges, intensities=np.zeros(0, np.float32))


def occupancy_grid(grid: OccupancyGrid, t: float) -> Any:
    """nav_msgs/msg/OccupancyGrid in the ``map`` frame (row 0 at the bottom, as ROS has it)."""
    rows, cols = grid.data.shape
    info = msg_class("nav_msgs/msg/MapMetaData")(
        map_load_time=stamp(t), resolution=float(grid.resolution), width=cols, height=rows,
        origin=pose_msg(grid.origin[0], grid.origin[1], 0.0))
    return msg_class(TYPES["map"])(header=header(t, MAP_FRAME), info=info,
                                   data=np.ascontiguousarray(grid.data, dtype=np.int8).reshape(-1))


def clock(t: float) -> Any:
    return msg_class(TYPES["clock"])(clock=stamp(t))


# ---------------------------------------------------------------------------- the run


class RosMessages:
    """Turns one run's snapshots into ROS 2 messages; :meth:`start` again after a reset."""

    def __init__(self, geometry: RunGeometry, world_map: OccupancyGrid | None = None) -> None:
        self.geometry = geometry
        self.world_map = world_map
        robots = geometry.meta["robots"]
        self.names = robot_names([r["name"] for r in robots])
        self._rates = {r["name"]: float((r.get("lidar") or {}).get("rate") or 0.0) for r in robots}

    def start(self, snapshot: Snapshot,
              wanted: Callable[[str], bool] = lambda topic: True) -> list[Outgoing]:
        """The latched messages, then the first instant's."""
        self._last_scan: dict[str, float] = {}
        self._last_imu: dict[str, float] = {}
        self._last_path: dict[str, Any] = {}
        self._last_grid: dict[str, tuple[float, Any]] = {}  # robot -> (time, grid data)
        self._last_obstacles: list[tuple[float, float, float]] = []
        self._last_refresh = -math.inf
        self._previous: dict[str, RobotSnapshot] = {}
        self._previous_time = snapshot.time
        return [*self.latched(snapshot), *self.messages(snapshot, wanted)]

    def latched(self, snapshot: Snapshot) -> Iterator[Outgoing]:
        """``/tf_static`` (each LiDAR on its robot) and ``/map``: sent once, kept for latecomers."""
        t, log_time = snapshot.time, nanoseconds(snapshot.time)
        mounts = [_transform(t, self.names[r.name].base_link, self.names[r.name].laser,
                             r.lidar_offset) for r in snapshot.robots if r.lidar_offset is not None]
        if mounts:
            yield Outgoing(TF_STATIC_TOPIC, TYPES["tf"], msg_class(TYPES["tf"])(transforms=mounts),
                           log_time)
        if self.world_map is not None:
            yield Outgoing(MAP_TOPIC, TYPES["map"], occupancy_grid(self.world_map, t), log_time)

    def messages(self, snap: Snapshot,
                 wanted: Callable[[str], bool] = lambda topic: True) -> list[Outgoing]:
        """What this instant sends, on the topics ``wanted`` accepts (so that nobody pays for a
        message no one receives)."""
        t, log_time = snap.time, nanoseconds(snap.time)
        out: list[Outgoing] = []
        refresh = t - self._last_refresh >= REFRESH_PERIOD - 1e-9
        if refresh:
            self._last_refresh = t
        if wanted(CLOCK_TOPIC):
            out.append(Outgoing(CLOCK_TOPIC, TYPES["clock"], clock(t), log_time))
        if wanted(TF_TOPIC):
            out.append(Outgoing(TF_TOPIC, TYPES["tf"], self._tf(snap), log_time))
        dt = t - self._previous_time
        for robot in snap.robots:
            out.extend(self._robot(robot, t, log_time, dt, refresh, wanted))
        if snap.obstacle_poses and wanted(OBSTACLES_TOPIC):
            markers = self._markers(snap, t, refresh)
            if markers is not None:
                out.append(Outgoing(OBSTACLES_TOPIC, TYPES["markers"], markers, log_time))
        self._previous = {r.name: r for r in snap.robots}
        self._previous_time = t
        return out

    # ------------------------------------------------------------------ per step
    def _tf(self, snap: Snapshot) -> Any:
        t, transforms = snap.time, []
        for robot in snap.robots:
            names = self.names[robot.name]
            estimate = robot.estimate if robot.estimate is not None else robot.odometry
            transforms.append(_transform(t, MAP_FRAME, names.odom,
                                         correction(estimate, robot.odometry)))
            transforms.append(_transform(t, names.odom, names.base_link, robot.odometry))
        return msg_class(TYPES["tf"])(transforms=transforms)

    def _robot(self, robot: RobotSnapshot, t: float, log_time: int, dt: float, refresh: bool,
               wanted: Callable[[str], bool]) -> Iterator[Outgoing]:
        names = self.names[robot.name]
        topic = names.topic
        if wanted(topic("odom")):
            yield Outgoing(topic("odom"), TYPES["odom"], self._odometry(robot, t, dt), log_time)
        if wanted(topic("ground_truth")):
            velocity = robot.velocity
            vy = velocity[1] if len(velocity) == 3 else 0.0
            yield Outgoing(topic("ground_truth"), TYPES["ground_truth"], _odometry_msg(
                t, MAP_FRAME, names.base_link, robot.pose, None,
                (velocity[0] if velocity else 0.0, vy, velocity[-1] if velocity else 0.0)),
                log_time)
        scan = robot.scan
        if scan is not None and self._last_scan.get(robot.name) != scan.time:
            self._last_scan[robot.name] = scan.time
            if wanted(topic("scan")):
                yield Outgoing(topic("scan"), TYPES["scan"],
                               laser_scan(scan, names.laser, self._rates.get(robot.name, 0.0)),
                               nanoseconds(scan.time))
        imu = robot.imu  # a snapshot's latest reading (None: no IMU)
        if imu is not None and self._last_imu.get(robot.name) != imu.time:
            self._last_imu[robot.name] = imu.time
            if wanted(topic("imu")):
                yield Outgoing(topic("imu"), TYPES["imu"], _imu(imu, names.base_link,
                                                                 robot.imu_noise),
                               nanoseconds(imu.time))
        if robot.localizer is not None and wanted(topic("pose")):
            yield Outgoing(topic("pose"), TYPES["pose"], msg_class(TYPES["pose"])(
                header=header(t, MAP_FRAME),
                pose=msg_class("geometry_msgs/msg/PoseWithCovariance")(
                    pose=pose_msg(*robot.localizer),
                    covariance=covariance6(robot.estimate_covariance))), log_time)
        if robot.grid is not None and wanted(topic("slam_map")):
            grid = self._built_map(robot, t)
            if grid is not None:
                yield Outgoing(topic("slam_map"), TYPES["slam_map"], grid, log_time)
        path = robot.path
        last = self._last_path.get(robot.name)
        if path is None or last is None:
            changed = (path is None) != (last is None)
        else:
            changed = path.shape != last.shape or not np.array_equal(path, last)
        if changed or (refresh and path is not None):
            self._last_path[robot.name] = path
            if wanted(topic("plan")):
                yield Outgoing(topic("plan"), TYPES["plan"], _path(path, t), log_time)

    def _built_map(self, robot: RobotSnapshot, t: float) -> Any:
        """The map a robot builds, at most every GRID_PERIOD and only when it changed."""
        last = self._last_grid.get(robot.name)
        if last is not None and t - last[0] < GRID_PERIOD - 1e-9:
            return None
        grid = robot.grid
        if last is not None and last[1].shape == grid.data.shape \
                and np.array_equal(last[1], grid.data):
            return None
        self._last_grid[robot.name] = (t, np.array(grid.data))
        return occupancy_grid(grid, t)

    def _odometry(self, robot: RobotSnapshot, t: float, dt: float) -> Any:
        """nav_msgs/msg/Odometry of the odometry estimate; its twist is the estimate's change
        since the last step, in the body frame (zero at the first instant)."""
        names = self.names[robot.name]
        before = self._previous.get(robot.name)
        twist = (0.0, 0.0, 0.0)
        if before is not None and dt > 0:
            dx, dy, dtheta = (float(a - b) for a, b in zip(robot.odometry, before.odometry))
            c, s = math.cos(float(before.odometry[2])), math.sin(float(before.odometry[2]))
            twist = ((c * dx + s * dy) / dt, (-s * dx + c * dy) / dt, dtheta / dt)
        return _odometry_msg(t, names.odom, names.base_link, robot.odometry,
                             robot.odometry_covariance, twist)

    def _markers(self, snap: Snapshot, t: float, refresh: bool) -> Any:
        """visualization_msgs/msg/MarkerArray of the movable obstacles that moved (all of
        them on a refresh); None when nothing changed."""
        markers = []
        for k, ((index, shapes), pose) in enumerate(zip(self.geometry.movable,
                                                        snap.obstacle_poses)):
            last = self._last_obstacles[k] if k < len(self._last_obstacles) else None
            if refresh or last is None or max(abs(a - b) for a, b in zip(pose, last)) > MOVED:
                markers.extend(_obstacle_markers(index, shapes, pose, t))
        self._last_obstacles = list(snap.obstacle_poses)
        return msg_class(TYPES["markers"])(markers=markers) if markers else None


def _odometry_msg(t: float, frame: str, child: str, pose, covariance3,
                  twist: tuple[float, float, float]) -> Any:
    vx, vy, omega = twist
    return msg_class(TYPES["odom"])(
        header=header(t, frame), child_frame_id=child,
        pose=msg_class("geometry_msgs/msg/PoseWithCovariance")(
            pose=pose_msg(*pose), covariance=covariance6(covariance3)),
        twist=msg_class("geometry_msgs/msg/TwistWithCovariance")(
            twist=msg_class("geometry_msgs/msg/Twist")(linear=_vector(vx, vy),
                                                       angular=_vector(0.0, 0.0, omega)),
            covariance=np.zeros(36)))


def _imu(reading, frame: str, noise: tuple[float, float]) -> Any:
    """sensor_msgs/msg/Imu: yaw rate and planar acceleration; no orientation (REP-145:
    covariance[0] = -1)."""
    gyro, accel = noise
    orientation_covariance = np.zeros(9)
    orientation_covariance[0] = -1.0
    return msg_class(TYPES["imu"])(
        header=header(reading.time, frame),
        orientation=msg_class("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=orientation_covariance,
        angular_velocity=_vector(0.0, 0.0, reading.yaw_rate),
        angular_velocity_covariance=np.diag([0.0, 0.0, gyro * gyro]).reshape(9),
        linear_acceleration=_vector(*reading.accel),
        linear_acceleration_covariance=np.diag([accel * accel, accel * accel, 0.0]).reshape(9))


def _path(path: np.ndarray | None, t: float) -> Any:
    points = np.zeros((0, 2)) if path is None else path
    poses = [msg_class("geometry_msgs/msg/PoseStamped")(
        header=header(t, MAP_FRAME), pose=pose_msg(x, y, heading_along(points, i)))
        for i, (x, y) in enumerate(points)]
    return msg_class(TYPES["plan"])(header=header(t, MAP_FRAME), poses=poses)


def _obstacle_markers(index: int, shapes, pose, t: float) -> list[Any]:
    """One marker per shape of obstacle ``index``: a cylinder for a circle, a closed line
    for a polygon or segment, placed at the obstacle's pose."""
    marker, color = msg_class("visualization_msgs/msg/Marker"), msg_class("std_msgs/msg/ColorRGBA")
    point = msg_class("geometry_msgs/msg/Point")
    out = []
    for j, shape in enumerate(shapes):
        points = np.asarray(shape.points, dtype=float).reshape(-1, 2)
        circle = shape.kind == "circle"
        if circle:
            centre = points[0] if len(points) else np.zeros(2)
            local = compose(pose, (centre[0], centre[1], 0.0))
            size = 2.0 * float(shape.radius)
            scale, line = _vector(size, size, MARKER_HEIGHT), []
        else:
            local = (float(pose[0]), float(pose[1]), float(pose[2]))
            scale = _vector(max(2.0 * float(shape.radius), 0.02), 0.0, 0.0)  # line width [m]
            line = [point(x=float(x), y=float(y), z=0.0) for x, y in points]
            if len(line) > 2:
                line.append(line[0])
        out.append(marker(
            header=header(t, MAP_FRAME), ns="obstacles", id=index * 1000 + j,
            type=3 if circle else 4,  # CYLINDER, LINE_STRIP
            action=0, pose=pose_msg(*local), scale=scale,
            color=color(r=0.8, g=0.5, b=0.2, a=1.0),
            lifetime=msg_class("builtin_interfaces/msg/Duration")(sec=0, nanosec=0),
            frame_locked=False, points=line, colors=[], texture_resource="",
            texture=msg_class("sensor_msgs/msg/CompressedImage")(
                header=header(t, ""), format="", data=np.zeros(0, np.uint8)),
            uv_coordinates=[], text="",
            mesh_resource="", mesh_file=msg_class("visualization_msgs/msg/MeshFile")(
                filename="", data=np.zeros(0, np.uint8)), mesh_use_embedded_materials=False))
    return out


class LiveMessages:
    """A live run's ROS 2 messages: its geometry read at (re)build, the moving obstacles'
    bodies, and the :class:`RosMessages` that turns each instant into messages."""

    def __init__(self, sim: Any, world_map: OccupancyGrid | None = None) -> None:
        geometry = geometry_of_sim(sim)
        self.bodies = movable_bodies(sim, geometry)
        self.ros = RosMessages(geometry, world_map)

    def start(self, sim: Any, wanted: Callable[[str], bool] = lambda topic: True
              ) -> list[Outgoing]:
        """The latched messages, then the present instant's."""
        return self.ros.start(snapshot_of_sim(sim, self.bodies), wanted)

    def step(self, sim: Any, wanted: Callable[[str], bool] = lambda topic: True
             ) -> list[Outgoing]:
        """The present instant's messages (after a step)."""
        return self.ros.messages(snapshot_of_sim(sim, self.bodies), wanted)

