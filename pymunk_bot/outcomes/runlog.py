"""Run logs: every robot's true pose, odometry, commands and LiDAR scans over time, in one .npz.

:class:`RunLogger` is a simulation observer (``sim.observers``), so the same logger serves
headless runs, the window and recordings. :func:`load_log` reads a log back for plots and
replay. The file holds plain numeric arrays and one JSON string (no pickles); its layout is
documented in docs/viewer.md.
"""
from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.results import write_atomic
from pymunk_bot.viewer.scene import ShapeGeometry, body_pose, world_geometry

if TYPE_CHECKING:
    from pymunk_bot.localization.recording import LocalizationRecorder

FORMAT = "pymunk-bot run log"
VERSION = 1
_PER_STEP = ("pose", "odometry", "command", "wheel_speeds", "velocity", "collisions", "goal",
             "goal_tolerance", "goal_reached", "teleop", "obstacle_pose")


@dataclass
class ScanLog:
    """The LiDAR scans of one robot: one row per scan taken."""

    time: np.ndarray  # (S,) when each scan was taken [s]
    pose: np.ndarray  # (S, 3) the robot's true pose at that moment
    ranges: np.ndarray  # (S, B) [m]; max_range where a beam returned nothing
    angles: np.ndarray  # (B,) beam angles relative to the heading [rad]
    offset: np.ndarray  # (3,) sensor mounting pose in the robot frame
    max_range: float  # [m]


@dataclass
class RunLog:
    """A recorded run. Per-step arrays have one row per step, row 0 being the start.

    ``pose``/``odometry`` (T, R, 3); ``command`` (commanded wheel speeds after the speed limit)
    and ``wheel_speeds`` (what the wheels turn at) (T, R, 2) [m/s]; ``velocity`` (T, R, 2) true
    (v [m/s], omega [rad/s]); ``collisions`` (T, R); ``goal`` (T, R, 2), NaN without a goal;
    ``goal_tolerance`` (T, R) [m]; ``goal_reached`` and ``teleop`` (T, R) bool;
    ``obstacle_pose`` (T, M, 3) for the M movable obstacles.
    """

    meta: dict
    time: np.ndarray
    pose: np.ndarray
    odometry: np.ndarray
    command: np.ndarray
    wheel_speeds: np.ndarray
    velocity: np.ndarray
    collisions: np.ndarray
    goal: np.ndarray
    goal_tolerance: np.ndarray
    goal_reached: np.ndarray
    teleop: np.ndarray
    obstacle_pose: np.ndarray
    scans: dict[str, ScanLog]
    # robots that localize or map: estimate, covariance, particles, built map (docs/viewer.md)
    localization: dict = field(default_factory=dict)

    @property
    def robot_names(self) -> list[str]:
        return [r["name"] for r in self.meta["robots"]]

    @property
    def dt(self) -> float:
        return float(self.meta["dt"])

    @property
    def size(self) -> tuple[float, float]:
        """Arena interior width and height [m]."""
        return float(self.meta["width"]), float(self.meta["height"])

    @property
    def origin(self) -> tuple[float, float]:
        """The arena's lower-left corner [m] (a map's origin; logs without one: 0, 0)."""
        x0, y0 = self.meta.get("origin", (0.0, 0.0))
        return float(x0), float(y0)

    def fixed_shapes(self) -> list[ShapeGeometry]:
        """The arena walls and fixed obstacles (world frame)."""
        return [_geometry_from_json(g, False) for g in self.meta["fixed"]]

    def movable_shapes(self) -> list[list[ShapeGeometry]]:
        """The shapes of each movable obstacle, in its body frame (see ``obstacle_pose``)."""
        return [[_geometry_from_json(g, True) for g in m["shapes"]] for m in self.meta["movable"]]

    def save(self, path: str | Path) -> None:
        """Write the log as a compressed .npz, atomically."""
        arrays = {name: getattr(self, name) for name in ("time", *_PER_STEP)}
        for name, scan in self.scans.items():
            arrays[f"scan.{name}.time"] = scan.time
            arrays[f"scan.{name}.pose"] = scan.pose
            arrays[f"scan.{name}.ranges"] = scan.ranges
            arrays[f"scan.{name}.angles"] = scan.angles
            arrays[f"scan.{name}.offset"] = scan.offset
        for name, track in self.localization.items():
            arrays.update(track.arrays(f"loc.{name}"))
        buffer = io.BytesIO()
        np.savez_compressed(buffer, meta=np.array(json.dumps(self.meta)), **arrays)
        write_atomic(path, buffer.getvalue())


# ---------------------------------------------------------------------------- recording


class RunLogger:
    """Records a simulation after every step; call :meth:`attach` once, :meth:`save` at the end.

    Scans are recorded when the LiDAR takes them, with the pose the robot had at that moment.
    A reset of the simulation (see :meth:`on_reset`) starts the log over.
    """

    def __init__(self) -> None:
        self._rows: dict[str, list] = {}
        self._scan_rows: dict[str, list] = {}
        self._last_scan: dict[str, object] = {}
        self._meta: dict = {}
        self._movable: list = []
        self._localization: LocalizationRecorder | None = None  # made by on_reset

    def attach(self, sim) -> "RunLogger":
        """Start logging ``sim`` from its present state and observe its every step."""
        sim.attach(self)  # on_reset now, then every step
        return self

    def on_reset(self, sim) -> None:
        """Forget what was logged and record ``sim`` as the new start."""
        fixed, movable = world_geometry(sim.world)
        self._movable = [sim.world.obstacles[i].body for i, _ in movable]
        robots = []
        for robot in sim.robots.values():
            lidar = robot.sensor("lidar")
            robots.append({
                "name": robot.name, "radius": robot.radius,
                "drive": robot.config.drive,
                "track_width": robot.spec.track_width,
                "max_wheel_speed": robot.spec.max_wheel_speed,
                "footprint": outline_json(robot),
                "lidar": None if lidar is None else {
                    "max_range": robot.config.lidar.max_range,
                    "rate": robot.config.lidar.rate},
            })
        self._meta = {
            "format": FORMAT, "version": VERSION, "scenario": sim.config.name,
            "seed": sim.seed, "dt": sim.dt, "width": sim.world.width,
            "height": sim.world.height, "origin": list(sim.world.extent[:2]), "robots": robots,
            "fixed": [_geometry_to_json(g) for g in fixed],
            "movable": [{"obstacle": i, "shapes": [_geometry_to_json(g) for g in shapes]}
                        for i, shapes in movable],
        }
        self._rows = {name: [] for name in ("time", *_PER_STEP)}
        self._scan_rows = {r.name: [] for r in sim.robots.values() if r.sensor("lidar") is not None}
        self._last_scan = {}
        from pymunk_bot.localization.recording import LocalizationRecorder

        self._localization = LocalizationRecorder(sim)
        self(sim)

    def __call__(self, sim) -> None:
        if self._localization is None:
            raise RuntimeError("the logger is not attached to a simulation: call attach(sim)")
        rows = self._rows
        robots = list(sim.robots.values())
        rows["time"].append(sim.time)
        rows["pose"].append([r.pose for r in robots])
        rows["odometry"].append([r.odometry.pose for r in robots])
        rows["command"].append([r.drive.target for r in robots])
        rows["wheel_speeds"].append([r.drive.wheel_speeds for r in robots])
        rows["velocity"].append([r.velocity for r in robots])
        rows["collisions"].append([r.collisions for r in robots])
        rows["goal"].append([r.goal if r.goal is not None else (np.nan, np.nan) for r in robots])
        rows["goal_tolerance"].append([r.goal_tolerance for r in robots])
        rows["goal_reached"].append([r.goal_reached for r in robots])
        rows["teleop"].append([r.overridden for r in robots])
        rows["obstacle_pose"].append([body_pose(b) for b in self._movable])
        for robot in robots:
            lidar = robot.sensor("lidar")
            scan = lidar.latest if lidar is not None else None
            if scan is not None and scan is not self._last_scan.get(robot.name):
                self._last_scan[robot.name] = scan
                self._scan_rows[robot.name].append((scan, robot.pose))
        self._localization(sim)

    def log(self) -> RunLog:
        """What has been recorded so far."""
        if not self._rows or self._localization is None:
            raise RuntimeError("the logger is not attached to a simulation")
        n_robots, n_movable = len(self._meta["robots"]), len(self._meta["movable"])
        shapes = {"pose": (n_robots, 3), "odometry": (n_robots, 3), "command": (n_robots, 2),
                  "wheel_speeds": (n_robots, 2), "velocity": (n_robots, 2),
                  "collisions": (n_robots,), "goal": (n_robots, 2),
                  "goal_tolerance": (n_robots,), "goal_reached": (n_robots,),
                  "teleop": (n_robots,), "obstacle_pose": (n_movable, 3)}
        dtypes = {"collisions": np.int64, "goal_reached": bool, "teleop": bool}
        arrays = {"time": np.array(self._rows["time"], dtype=float)}
        steps = len(arrays["time"])
        for name, shape in shapes.items():
            arrays[name] = np.array(self._rows[name], dtype=dtypes.get(name, float)).reshape(
                (steps, *shape))
        scans = {}
        for name, rows in self._scan_rows.items():
            if rows:
                first = rows[0][0]
                angles, offset = first.angles, first.offset
                ranges = np.array([s.ranges for s, _ in rows], dtype=np.float32)
            else:
                angles, offset, ranges = np.empty(0), (0.0, 0.0, 0.0), np.empty((0, 0), np.float32)
            max_range = next(r["lidar"]["max_range"] for r in self._meta["robots"]
                             if r["name"] == name)
            scans[name] = ScanLog(
                time=np.array([s.time for s, _ in rows], dtype=float),
                pose=np.array([p for _, p in rows], dtype=float).reshape(-1, 3),
                ranges=ranges, angles=np.asarray(angles, dtype=float),
                offset=np.asarray(offset, dtype=float), max_range=float(max_range))
        return RunLog(meta=dict(self._meta), scans=scans,
                      localization=self._localization.tracks(float(arrays["time"][-1])), **arrays)

    def save(self, path: str | Path) -> None:
        """Write what has been recorded to ``path`` (.npz), atomically."""
        self.log().save(path)


# ---------------------------------------------------------------------------- loading


def load_log(path: str | Path) -> RunLog:
    """Read a run log written by :class:`RunLogger`; a bad file raises ScenarioError."""
    source = str(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            files = dict(data.items())
    except FileNotFoundError:
        raise ScenarioError(source, "", "file not found") from None
    except IsADirectoryError:
        raise ScenarioError(source, "", "is a directory, not a run log") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError):
        raise ScenarioError(source, "", "not a run log (an .npz written by "
                                        "`pymunk-bot run --log`)") from None
    try:
        meta = json.loads(str(files.pop("meta")))
    except (KeyError, ValueError):
        raise ScenarioError(source, "", "not a run log: no valid 'meta' entry") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ScenarioError(source, "", "not a pymunk-bot run log")
    if meta.get("version") != VERSION:
        raise ScenarioError(source, "", f"run log version {meta.get('version')} is not "
                                        f"supported (this pymunk-bot reads version {VERSION})")
    missing = [name for name in ("time", *_PER_STEP) if name not in files]
    if missing:
        raise ScenarioError(source, "", f"run log is missing {', '.join(missing)}")
    try:
        log = _assemble(meta, files)
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise ScenarioError(source, "", f"run log is damaged ({type(exc).__name__}: "
                                        f"{exc})") from None
    n = log.time.shape[0]
    per_step = [getattr(log, name) for name in _PER_STEP]
    if n == 0 or any(a.shape[0] != n for a in per_step) or log.pose.shape[1:] != (
            len(log.robot_names), 3):
        raise ScenarioError(source, "", "run log is damaged: its arrays do not fit together")
    return log


def _assemble(meta: dict, files: dict) -> RunLog:
    scans = {}
    for robot in meta["robots"]:
        name = robot["name"]
        if robot.get("lidar") is None or f"scan.{name}.time" not in files:
            continue
        scans[name] = ScanLog(
            time=files[f"scan.{name}.time"], pose=files[f"scan.{name}.pose"],
            ranges=files[f"scan.{name}.ranges"], angles=files[f"scan.{name}.angles"],
            offset=files[f"scan.{name}.offset"], max_range=float(robot["lidar"]["max_range"]))
    absent = [k for k in ("dt", "width", "height", "scenario", "seed", "fixed", "movable")
              if k not in meta]
    if absent:
        raise KeyError(absent[0])
    per_step = {name: files[name] for name in ("time", *_PER_STEP)}
    from pymunk_bot.localization.recording import LocalizationTrack

    tracks = {r["name"]: LocalizationTrack.from_arrays(files, f"loc.{r['name']}")
              for r in meta["robots"] if f"loc.{r['name']}.estimate" in files}
    return RunLog(meta=meta, scans=scans, localization=tracks, **per_step)


def _geometry_to_json(g: ShapeGeometry) -> dict:
    return {"kind": g.kind, "points": g.points.tolist(), "radius": g.radius, "wall": g.wall,
            "group": g.group}


def _geometry_from_json(d: dict, movable: bool) -> ShapeGeometry:
    return ShapeGeometry(d["kind"], np.asarray(d["points"], dtype=float).reshape(-1, 2),
                         float(d["radius"]), movable, bool(d["wall"]), int(d["group"]))


def outline_json(robot) -> list | None:
    """A robot's footprint outline (robot frame) for views; None for a disc about its pose."""
    from pymunk_bot.geometry.footprint import drawn_outline
    outline = drawn_outline(getattr(robot.spec, "footprint", None))
    return None if outline is None else outline.tolist()
