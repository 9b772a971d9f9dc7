"""Where the frames come from: a live simulation or a saved run log.

Both give :class:`~pymunk_bot.viewer.scene.Scene` snapshots and advance one step at a time,
so the window and the video recorder treat them alike. Only a live source accepts goals and
teleop; it changes the simulation through its public API and nothing else.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.geometry.footprint import drawn_outline
from pymunk_bot.viewer.scene import RobotView, Scene, ShapeView, body_pose, scan_end_points, world_geometry

TRAIL_SPACING = 0.01  # [m]; a trail point is added once the robot has moved this far
TRAIL_MAX_POINTS = 20_000  # older halves are thinned beyond this, so memory stays bounded


class LiveSource:
    """A running :class:`~pymunk_bot.engine.simulation.Simulation`, plus the trails and scans seen so far.

    Step it only through :meth:`step` so that every scan is seen with the pose it was taken at.
    """

    interactive = True

    def __init__(self, sim) -> None:
        self.sim = sim
        self.rebuild()

    def rebuild(self) -> None:
        """Start over from the simulation as it is now (after a reset)."""
        sim = self.sim
        fixed, movable = world_geometry(sim.world)
        self._fixed = [g.placed((0.0, 0.0, 0.0)) for g in fixed]
        self._movable = [(sim.world.obstacles[i].body, shapes) for i, shapes in movable]
        self._index = {name: i for i, name in enumerate(sim.robots)}
        self._trails: dict[str, list[tuple[float, float]]] = {}
        self._scans: dict[str, tuple] = {}
        self._seen_scan: dict[str, object] = {}
        self.observe()

    # ------------------------------------------------------------------ clock
    @property
    def dt(self) -> float:
        return self.sim.dt

    @property
    def steps(self) -> int:
        return self.sim.steps

    @property
    def time(self) -> float:
        return self.sim.time

    @property
    def at_end(self) -> bool:
        return False  # a simulation can always go on

    @property
    def robot_names(self) -> list[str]:
        return list(self.sim.robots)

    @property
    def size(self) -> tuple[float, float]:
        """Arena interior width and height [m]."""
        return self.sim.world.width, self.sim.world.height

    @property
    def origin(self) -> tuple[float, float]:
        """The arena's lower-left corner [m] (a map's origin; else 0, 0)."""
        return self.sim.world.extent[0], self.sim.world.extent[1]

    def step(self) -> None:
        """One physics step, then note trails and new scans."""
        self.sim.step()
        self.observe()

    def reset(self) -> None:
        """Rebuild the simulation from its config and seed; observers (e.g. a logger) stay."""
        self.sim.reset()
        self.rebuild()

    def observe(self) -> None:
        """Note trails and new scans after a step the simulation took (the source's own
        :meth:`step`, or someone else's: an env's)."""
        for name, robot in self.sim.robots.items():
            x, y, _ = robot.pose
            trail = self._trails.setdefault(name, [(x, y)])
            lx, ly = trail[-1]
            if math.hypot(x - lx, y - ly) >= TRAIL_SPACING:
                trail.append((x, y))
                if len(trail) > TRAIL_MAX_POINTS:
                    half = len(trail) // 2
                    trail[:half] = trail[:half:2]
            lidar = robot.sensor("lidar")
            scan = getattr(lidar, "latest", None) if lidar is not None else None
            if scan is not None and scan is not self._seen_scan.get(name):
                self._seen_scan[name] = scan
                self._scans[name] = scan_end_points(robot.pose, scan)

    # ------------------------------------------------------------------ interaction
    def robot(self, name: str):
        """The live Robot called ``name``."""
        return self.sim.robots[name]

    # ------------------------------------------------------------------ drawing
    def scene(self) -> Scene:
        """A snapshot of the present state."""
        shapes: list[ShapeView] = list(self._fixed)
        for body, geometry in self._movable:
            pose = body_pose(body)
            shapes.extend(g.placed(pose) for g in geometry)
        robots = []
        for name, robot in self.sim.robots.items():
            controller = robot.controller
            path = controller.debug_path() if controller is not None else None
            origin, points, hit = self._scans.get(name, (None, None, None))
            v, omega = robot.velocity
            robots.append(RobotView(
                name=name, index=self._index[name], pose=robot.pose, radius=robot.radius,
                odometry=robot.odometry.pose, velocity=(float(v), float(omega)),
                goal=robot.goal, goal_tolerance=robot.goal_tolerance,
                goal_reached=robot.goal_reached,
                nav_goal=robot.nav_goal if robot.nav_goal not in (None, robot.goal) else None,
                path=None if not path else np.asarray(path, dtype=float).reshape(-1, 2),
                trail=np.asarray(self._trails[name], dtype=float),
                scan_origin=origin, scan_points=points, scan_hit=hit,
                collisions=robot.collisions,
                status=_status(controller),
                teleop=robot.overridden, footprint=drawn_outline(robot.spec.footprint),
                steering=getattr(robot.drive, "steering_angle", None),
                wheelbase=float(getattr(robot.drive, "wheelbase", 0.0)),
                **_live_localization(robot)))
        return Scene(self.sim.world.width, self.sim.world.height, self.sim.time, shapes, robots,
                     self.sim.config.name, self.origin)


def _live_localization(robot) -> dict:
    """The RobotView fields of a robot's localizer and map, when the scenario names them."""
    fields: dict = {}
    if getattr(robot, "localization_score", None) is not None:
        localizer = robot.localizer
        fields["estimate"] = np.array(localizer.pose, dtype=float)
        fields["covariance"] = np.array(localizer.covariance, dtype=float)
        fields["particles"] = localizer.debug().get("particles")
    if getattr(robot, "mapper", None) is not None:
        fields["built_map"] = robot.mapper.grid
    return fields


def _replay_localization(track, i: int, time: float) -> dict:
    """The same fields from a run log's LocalizationTrack at step ``i``."""
    if track is None:
        return {}
    return {"estimate": track.estimate[i], "covariance": track.covariance[i],
            "particles": track.cloud_at(time), "built_map": track.map_at(time)}


def _status(controller) -> str:
    """The controller's status for the HUD, with its reason when it has given up."""
    if controller is None:
        return "no controller"
    if controller.status == "failed" and controller.message:
        return f"failed: {controller.message}"
    return controller.status


class ReplaySource:
    """A saved :class:`~pymunk_bot.outcomes.runlog.RunLog`, played back one logged step at a time."""

    interactive = False

    def __init__(self, log) -> None:
        self.log = log
        self.index = 0
        self._fixed = [g.placed((0.0, 0.0, 0.0)) for g in log.fixed_shapes()]
        self._movable = log.movable_shapes()

    @property
    def dt(self) -> float:
        return self.log.dt

    @property
    def steps(self) -> int:
        return self.index

    @property
    def time(self) -> float:
        return float(self.log.time[self.index])

    @property
    def at_end(self) -> bool:
        return self.index >= len(self.log.time) - 1

    @property
    def robot_names(self) -> list[str]:
        return self.log.robot_names

    @property
    def size(self) -> tuple[float, float]:
        """Arena interior width and height [m]."""
        return self.log.size

    @property
    def origin(self) -> tuple[float, float]:
        """The arena's lower-left corner [m]."""
        return self.log.origin

    def step(self) -> None:
        """The next logged step (stays on the last one)."""
        if not self.at_end:
            self.index += 1

    def reset(self) -> None:
        """Back to the start of the log."""
        self.index = 0

    def seek(self, steps: int) -> None:
        """Jump by ``steps`` logged steps (negative: back), within the log."""
        self.index = int(np.clip(self.index + steps, 0, len(self.log.time) - 1))

    def scene(self) -> Scene:
        log, i = self.log, self.index
        shapes = list(self._fixed)
        for k, geometry in enumerate(self._movable):
            shapes.extend(g.placed(log.obstacle_pose[i, k]) for g in geometry)
        robots = []
        for j, meta in enumerate(log.meta["robots"]):
            name = meta["name"]
            goal = log.goal[i, j]
            origin = points = hit = None
            scans = log.scans.get(name)
            if scans is not None and len(scans.time):
                # The latest scan taken at or before this step.
                k = int(np.searchsorted(scans.time, log.time[i] + 1e-9, side="right")) - 1
                if k >= 0:
                    origin, points, hit = scan_end_points(scans.pose[k], _Scan(scans, k))
            v, omega = log.velocity[i, j]
            robots.append(RobotView(
                name=name, index=j, pose=log.pose[i, j], radius=float(meta["radius"]),
                odometry=log.odometry[i, j], velocity=(float(v), float(omega)),
                goal=None if np.isnan(goal).any() else (float(goal[0]), float(goal[1])),
                goal_tolerance=float(log.goal_tolerance[i, j]),
                goal_reached=bool(log.goal_reached[i, j]),
                trail=log.pose[: i + 1, j, :2], scan_origin=origin, scan_points=points,
                scan_hit=hit, collisions=int(log.collisions[i, j]),
                teleop=bool(log.teleop[i, j]),
                footprint=None if not meta.get("footprint") else np.asarray(meta["footprint"]),
                **_replay_localization(getattr(log, "localization", {}).get(name), i,
                                       float(log.time[i]))))
        width, height = log.size
        return Scene(width, height, self.time, shapes, robots, f"replay: {log.meta['scenario']}",
                     log.origin)


class _Scan:
    """One logged scan with the fields scan_end_points reads."""

    def __init__(self, scans, k: int) -> None:
        self.ranges = scans.ranges[k]
        self.angles = scans.angles
        self.offset = scans.offset
        self.max_range = scans.max_range
