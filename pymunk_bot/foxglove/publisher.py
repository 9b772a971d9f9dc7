"""The channel layer: snapshots of a run -> Foxglove messages, for files and live views alike.

:class:`Publisher` turns :class:`~.snapshot.Snapshot` s into messages on a
:class:`foxglove.Context`; whatever sinks the context has (an MCAP file, a WebSocket server)
receive them. :class:`SimPublisher` is the simulation observer that feeds it after every step.
What goes where, and how often, is listed in docs/foxglove.md.
"""
from __future__ import annotations

import foxglove
import numpy as np
from foxglove.messages import (FrameTransform, FrameTransforms, Grid, LaserScan, Log, LogLevel,
                               PackedElementField, PackedElementFieldNumericType, PoseInFrame,
                               PosesInFrame, Quaternion, SceneUpdate, Vector2, Vector3)

from pymunk_bot.foxglove import scene
from pymunk_bot.foxglove.channels import OBSTACLE_POSES_SCHEMA, ROBOT_STATE_SCHEMA, Channels
from pymunk_bot.foxglove.frames import (LOG_TOPIC, OBSTACLES_TOPIC, SCENE_TOPIC, TF_TOPIC, WORLD_FRAME, base_frame,
                     lidar_frame, nanoseconds, robot_topic, yaw_quaternion)
from pymunk_bot.foxglove.snapshot import (RobotSnapshot, RunGeometry, Snapshot, geometry_of_sim, movable_bodies,
                       snapshot_of_sim)

REFRESH_PERIOD = 1.0  # [s] simulated: the whole scene and paths again, for late viewers and seeks
GRID_PERIOD = 1.0  # [s] simulated: at most this often a changed occupancy grid
MOVED = 1e-6  # [m] or [rad]: a movable obstacle that moved less is not sent again


class Publisher:
    """Publishes one run's snapshots; call :meth:`start` first and again after a reset."""

    def __init__(self, context: foxglove.Context) -> None:
        self.channels = Channels(context)
        self.geometry: RunGeometry | None = None

    def start(self, geometry: RunGeometry, snapshot: Snapshot) -> None:
        """Begin (or begin again) with the run's static geometry and its first instant."""
        self.geometry = geometry
        self._index = {r["name"]: i for i, r in enumerate(geometry.meta["robots"])}
        self._outlines = {r["name"]: r.get("footprint") for r in geometry.meta["robots"]}
        self._last_refresh = -np.inf
        self._last_scan: dict[str, float] = {}
        self._last_path: dict[str, np.ndarray | None] = {}
        self._last_grid: dict[str, tuple[float, object, bytes]] = {}
        self._last_goal: dict[str, tuple | None] = {}
        self._last_obstacles: list[tuple[float, float, float]] = []
        self._previous = {r.name: r for r in snapshot.robots}
        self.publish(snapshot)

    def publish(self, snap: Snapshot) -> None:
        """Send what changed at this instant (see the module docstring)."""
        geometry = self.geometry
        if geometry is None:
            raise RuntimeError("Publisher.publish: call start() with the run's geometry first")
        t, log_time = snap.time, nanoseconds(snap.time)
        refresh = t - self._last_refresh >= REFRESH_PERIOD - 1e-9
        if refresh:
            self._last_refresh = t
        self._transforms(snap, log_time)
        for robot in snap.robots:
            self._robot(robot, t, log_time, refresh)
            self._events(robot, t, log_time)
        self._scene(snap, geometry, t, log_time, refresh)
        self._previous = {r.name: r for r in snap.robots}

    def log_event(self, t: float, name: str, message: str, level=LogLevel.Info) -> None:
        """One line on the log channel at simulated time ``t``."""
        channel = self.channels.wanted(LOG_TOPIC, "Log")
        if channel is not None:
            channel.log(Log(timestamp=scene.timestamp(t), level=level, message=message, name=name),
                        log_time=nanoseconds(t))

    def close(self) -> None:
        self.channels.close()

    # ------------------------------------------------------------------ per step
    def _transforms(self, snap: Snapshot, log_time: int) -> None:
        channel = self.channels.wanted(TF_TOPIC, "FrameTransforms")
        if channel is None:
            return
        stamp = scene.timestamp(snap.time)
        transforms = []
        for robot in snap.robots:
            transforms.append(_transform(stamp, WORLD_FRAME, base_frame(robot.name), robot.pose))
            if robot.lidar_offset is not None:
                transforms.append(_transform(stamp, base_frame(robot.name),
                                             lidar_frame(robot.name), robot.lidar_offset))
        channel.log(FrameTransforms(transforms=transforms), log_time=log_time)

    def _robot(self, robot: RobotSnapshot, t: float, log_time: int, refresh: bool) -> None:
        name, channels = robot.name, self.channels
        for what, pose in (("ground_truth", robot.pose), ("odometry", robot.odometry),
                           ("localization", robot.localizer)):
            if pose is None:
                continue
            channel = channels.wanted(robot_topic(name, what), "PoseInFrame")
            if channel is not None:
                channel.log(PoseInFrame(timestamp=scene.timestamp(t), frame_id=WORLD_FRAME,
                                        pose=scene.pose_msg(*(float(v) for v in pose))),
                            log_time=log_time)
        channel = channels.wanted(robot_topic(name, "state"), ROBOT_STATE_SCHEMA)
        if channel is not None:
            channel.log(_state(robot, t), log_time=log_time)
        scan = robot.scan
        if scan is not None and self._last_scan.get(name) != scan.time:
            self._last_scan[name] = scan.time
            channel = channels.wanted(robot_topic(name, "scan"), "LaserScan")
            if channel is not None:
                channel.log(_laser_scan(name, scan), log_time=nanoseconds(scan.time))
        self._path(robot, t, log_time, refresh)
        if robot.grid is not None:
            self._grid(robot, t, log_time)

    def _path(self, robot: RobotSnapshot, t: float, log_time: int, refresh: bool) -> None:
        last = self._last_path.get(robot.name)
        path = robot.path
        if path is None or last is None:
            changed = (path is None) != (last is None)
        else:
            changed = path.shape != last.shape or not np.array_equal(path, last)
        if not (changed or (refresh and path is not None)):
            return
        self._last_path[robot.name] = path
        channel = self.channels.wanted(robot_topic(robot.name, "path"), "PosesInFrame")
        if channel is not None:
            poses = [] if path is None else [scene.pose_msg(float(x), float(y),
                                                            heading_along(path, i))
                                             for i, (x, y) in enumerate(path)]
            channel.log(PosesInFrame(timestamp=scene.timestamp(t), frame_id=WORLD_FRAME,
                                     poses=poses), log_time=log_time)

    def _grid(self, robot: RobotSnapshot, t: float, log_time: int) -> None:
        grid = robot.grid
        last = self._last_grid.get(robot.name)
        if last is not None and t - last[0] < GRID_PERIOD - 1e-9:
            return
        data = np.ascontiguousarray(grid.data, dtype=np.int8).tobytes()
        if last is not None and last[1] == (grid.resolution, grid.origin, grid.data.shape) \
                and last[2] == data:
            return
        self._last_grid[robot.name] = (t, (grid.resolution, grid.origin, grid.data.shape), data)
        channel = self.channels.wanted(robot_topic(robot.name, "map"), "Grid")
        if channel is None:
            return
        # Row 0 is the bottom row, at the grid's origin: the layout Foxglove's Grid expects.
        channel.log(Grid(
            timestamp=scene.timestamp(t), frame_id=WORLD_FRAME,
            pose=scene.pose_msg(float(grid.origin[0]), float(grid.origin[1]), 0.0),
            column_count=grid.cols, cell_size=Vector2(x=grid.resolution, y=grid.resolution),
            row_stride=grid.cols, cell_stride=1,
            fields=[PackedElementField(name="occupancy", offset=0,
                                       type=PackedElementFieldNumericType.Int8)],
            data=data), log_time=log_time)

    def _events(self, robot: RobotSnapshot, t: float, log_time: int) -> None:
        before = self._previous.get(robot.name)
        if before is None:
            return
        name = robot.name
        if robot.collisions > before.collisions:
            self.log_event(t, name, f"{name}: contact begins (collision {robot.collisions})",
                           LogLevel.Warning)
        if robot.goal_reached and not before.goal_reached:
            self.log_event(t, name, f"{name}: goal reached at t = {t:.2f} s")
        if robot.status != before.status:
            level = LogLevel.Error if robot.status == "failed" else LogLevel.Info
            why = f" ({robot.status_message})" if robot.status_message else ""
            self.log_event(t, name, f"{name}: controller {before.status or 'none'} -> "
                                    f"{robot.status or 'none'}{why}", level)

    def _scene(self, snap: Snapshot, geometry: RunGeometry, t: float, log_time: int,
               refresh: bool) -> None:
        poses = snap.obstacle_poses
        if poses:
            channel = self.channels.wanted(OBSTACLES_TOPIC, OBSTACLE_POSES_SCHEMA)
            if channel is not None:
                channel.log({"time": t, "obstacles": [i for i, _ in geometry.movable],
                             "poses": [list(p) for p in poses]}, log_time=log_time)
        channel = self.channels.wanted(SCENE_TOPIC, "SceneUpdate")
        if channel is None:
            return
        entities, deletions = [], []
        if refresh:
            entities.append(scene.arena_entity(geometry.fixed, t))
            entities.extend(scene.robot_entity(r.name, self._index.get(r.name, 0), r.radius, t,
                                               self._outlines.get(r.name))
                            for r in snap.robots)
        for k, ((index, shapes), pose) in enumerate(zip(geometry.movable, poses)):
            last = self._last_obstacles[k] if k < len(self._last_obstacles) else None
            if refresh or last is None or max(abs(a - b) for a, b in zip(pose, last)) > MOVED:
                entities.append(scene.obstacle_entity(index, shapes, pose, t))
        self._last_obstacles = list(poses)
        for r in snap.robots:
            goal = None if r.goal is None else (r.goal, r.goal_tolerance, r.goal_reached)
            if not refresh and goal == self._last_goal.get(r.name, False):
                continue
            self._last_goal[r.name] = goal
            if goal is None:
                deletions.append(scene.deletion(f"goal/{r.name}", t))
            else:
                entities.append(scene.goal_entity(r.name, self._index.get(r.name, 0), *goal, t))
        if entities or deletions:
            channel.log(SceneUpdate(entities=entities, deletions=deletions), log_time=log_time)


class SimPublisher:
    """A simulation observer (``sim.observers``) publishing every step through a Publisher."""

    def __init__(self, publisher: Publisher) -> None:
        self.publisher = publisher
        self._bodies: list = []

    def attach(self, sim) -> "SimPublisher":
        """Publish ``sim``'s present state, then every step."""
        sim.attach(self)  # on_reset now, then every step
        return self

    def on_reset(self, sim) -> None:
        geometry = geometry_of_sim(sim)
        self._bodies = movable_bodies(sim, geometry)
        if self.publisher.geometry is not None:
            self.publisher.log_event(sim.time, "sim", f"simulation reset (seed {sim.seed})")
        self.publisher.start(geometry, snapshot_of_sim(sim, self._bodies))

    def __call__(self, sim) -> None:
        self.publisher.publish(snapshot_of_sim(sim, self._bodies))


# ---------------------------------------------------------------------------- messages


def _transform(stamp, parent: str, child: str, pose) -> FrameTransform:
    x, y, theta = (float(v) for v in pose)
    qx, qy, qz, qw = yaw_quaternion(theta)
    return FrameTransform(timestamp=stamp, parent_frame_id=parent, child_frame_id=child,
                          translation=Vector3(x=x, y=y, z=0.0),
                          rotation=Quaternion(x=qx, y=qy, z=qz, w=qw))


def _laser_scan(name: str, scan) -> LaserScan:
    """A scan in its mount frame: our beam angles include the mount's yaw, Foxglove's do not."""
    angles = np.asarray(scan.angles, dtype=float)
    yaw = float(scan.offset[2]) if len(scan.offset) == 3 else 0.0
    return LaserScan(timestamp=scene.timestamp(scan.time), frame_id=lidar_frame(name),
                     pose=scene.pose_msg(0.0, 0.0, 0.0),
                     start_angle=float(angles[0]) - yaw, end_angle=float(angles[-1]) - yaw,
                     ranges=np.asarray(scan.ranges, dtype=float).tolist())


def _state(robot: RobotSnapshot, t: float) -> dict:
    velocity = list(robot.velocity)
    return {"time": t, "pose": [float(v) for v in robot.pose],
            "odometry": [float(v) for v in robot.odometry],
            "v": velocity[0] if velocity else 0.0, "omega": velocity[-1] if velocity else 0.0,
            "velocity": velocity,
            "command": None if robot.command is None else list(robot.command),
            "wheel_speeds": None if robot.wheel_speeds is None else list(robot.wheel_speeds),
            "collisions": robot.collisions, "goal": None if robot.goal is None else list(robot.goal),
            "goal_tolerance": robot.goal_tolerance, "goal_reached": robot.goal_reached,
            "teleop": robot.teleop, "status": robot.status}


def heading_along(path: np.ndarray, i: int) -> float:
    """Direction of travel at point ``i`` of a path (towards the next point; the last keeps
    the previous segment's)."""
    if len(path) < 2:
        return 0.0
    j = min(i, len(path) - 2)
    dx, dy = path[j + 1] - path[j]
    return float(np.arctan2(dy, dx))
