"""MCAP -> :class:`~pymunk_bot.outcomes.runlog.RunLog`, so ``replay`` and ``plot`` read MCAP too.

Reads what :mod:`.mcap_log` writes: the geometry from the ``pymunk_bot`` metadata record, the
per-step state from each robot's JSON state channel, scans from the ``foxglove.LaserScan``
channels (decoded from protobuf), movable obstacles from their JSON channel. A file recorded
across a ``sim.reset()`` holds several runs; the last one is read.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable, TypeVar

import numpy as np

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.runlog import FORMAT, RunLog, ScanLog
from pymunk_bot.foxglove import require
from pymunk_bot.foxglove.frames import METADATA_NAME, OBSTACLES_TOPIC, robot_topic

MAX_STEPS = 10_000_000  # refuse absurd files rather than exhaust memory

Row = TypeVar("Row")


def load_mcap(path: str | Path) -> RunLog:
    """Read an MCAP written by ``pymunk-bot run --log run.mcap`` (or ``convert``)."""
    require("mcap", "replay")
    decoder = require("mcap_protobuf.decoder", "replay")
    from mcap.exceptions import McapError
    from mcap.reader import make_reader

    source = str(path)
    try:
        stream = open(path, "rb")
    except FileNotFoundError:
        raise ScenarioError(source, "", "file not found") from None
    except IsADirectoryError:
        raise ScenarioError(source, "", "is a directory, not a run log") from None
    with stream:
        try:
            reader = make_reader(stream)
            meta = _meta(reader, source)
            log = _read(reader, meta, source, decoder.DecoderFactory())
        except (McapError, ValueError, KeyError, TypeError, IndexError, EOFError) as exc:
            raise ScenarioError(source, "", f"not a readable MCAP run log ({type(exc).__name__}: "
                                            f"{exc})") from None
    return log


def _meta(reader, source: str) -> dict:
    for record in reader.iter_metadata():
        if record.name == METADATA_NAME and "runlog" in record.metadata:
            meta = json.loads(record.metadata["runlog"])
            if isinstance(meta, dict) and meta.get("format") == FORMAT:
                return meta
    raise ScenarioError(source, "", "not an MCAP written by pymunk-bot (no 'pymunk_bot' "
                                    "metadata); write one with `pymunk-bot run --log run.mcap`")


def _last_run(rows: list[tuple[float, Row]]) -> list[tuple[float, Row]]:
    """The rows after the last time the clock went back (a reset), in the order written."""
    start = 0
    for i in range(1, len(rows)):
        if rows[i][0] < rows[i - 1][0] - 1e-12:
            start = i
    return rows[start:]


def _read(reader, meta: dict, source: str, factory) -> RunLog:
    robots = [r["name"] for r in meta["robots"]]
    state_topics = {robot_topic(name, "state"): name for name in robots}
    scan_topics = {robot_topic(name, "scan"): name for name in robots}
    states: dict[str, list[tuple[float, dict]]] = {name: [] for name in robots}
    scans: dict[str, list[tuple[float, Any]]] = {name: [] for name in robots}  # protobuf scans
    obstacles: list[tuple[float, list]] = []
    topics = [*state_topics, *scan_topics, OBSTACLES_TOPIC]
    decoders: dict[int, Callable[[bytes], Any]] = {}  # channel id -> protobuf decoder
    for schema, channel, message in reader.iter_messages(topics=topics, log_time_order=False):
        topic = channel.topic
        if topic in scan_topics:
            if channel.id not in decoders:
                decoders[channel.id] = factory.decoder_for(channel.message_encoding, schema)
            scans[scan_topics[topic]].append((message.log_time / 1e9,
                                              decoders[channel.id](message.data)))
        elif topic in state_topics:
            row = json.loads(message.data)
            states[state_topics[topic]].append((float(row["time"]), row))
        else:
            row = json.loads(message.data)
            obstacles.append((float(row["time"]), row["poses"]))
        if len(obstacles) > MAX_STEPS or any(len(v) > MAX_STEPS for v in states.values()):
            raise ScenarioError(source, "", f"more than {MAX_STEPS} steps: too long to replay")
    rows = {name: _last_run(states[name]) for name in robots}
    steps = len(rows[robots[0]]) if robots else 0
    if steps == 0 or any(len(r) != steps for r in rows.values()):
        raise ScenarioError(source, "", "run log is damaged: robot state channels missing or "
                                        "of different lengths")
    time = np.array([t for t, _ in rows[robots[0]]])
    per_robot = [[row for _, row in rows[name]] for name in robots]

    def stack(key: str, width: int | None = None, dtype=float) -> np.ndarray:
        out = []
        for i in range(steps):
            values = []
            for robot_rows in per_robot:
                value = robot_rows[i].get(key)
                if value is None and width:
                    value = [np.nan] * width
                values.append(value)
            out.append(values)
        return np.array(out, dtype=dtype)

    velocity = stack("velocity")
    velocity = np.stack([velocity[..., 0], velocity[..., -1]], axis=-1)  # (v, omega)
    n_movable = len(meta["movable"])
    moved = _last_run(obstacles)
    obstacle_pose = (np.array([p for _, p in moved], dtype=float).reshape(-1, n_movable, 3)
                     if n_movable else np.zeros((steps, 0, 3)))
    if len(obstacle_pose) != steps:
        raise ScenarioError(source, "", "run log is damaged: obstacle poses do not fit the steps")
    pose = stack("pose")
    return RunLog(
        meta=meta, time=time, pose=pose, odometry=stack("odometry"),
        command=stack("command", 2), wheel_speeds=stack("wheel_speeds", 2), velocity=velocity,
        collisions=stack("collisions", dtype=np.int64), goal=stack("goal", 2),
        goal_tolerance=stack("goal_tolerance"), goal_reached=stack("goal_reached", dtype=bool),
        teleop=stack("teleop", dtype=bool), obstacle_pose=obstacle_pose,
        scans={name: _scan_log(meta["robots"][j], _last_run(scans[name]), time, pose[:, j])
               for j, name in enumerate(robots) if meta["robots"][j].get("lidar")})


def _scan_log(robot: dict, rows: list, time: np.ndarray, pose: np.ndarray) -> ScanLog:
    lidar = robot["lidar"]
    offset = np.asarray(lidar.get("offset", (0.0, 0.0, 0.0)), dtype=float)
    if not rows:
        return ScanLog(np.empty(0), np.empty((0, 3)), np.empty((0, 0), np.float32), np.empty(0),
                       offset, float(lidar["max_range"]))
    first = rows[0][1]
    beams = len(first.ranges)
    # Our beam angles are relative to the heading (mount yaw included); the message's to the mount.
    angles = np.linspace(first.start_angle, first.end_angle, beams) + offset[2]
    times = np.array([t for t, _ in rows])
    at = np.clip(np.searchsorted(time, times - 1e-6), 0, len(time) - 1)
    # Scans are taken at the end of a step: give them that step's exact time (ns round off).
    times = np.where(np.abs(time[at] - times) < 1e-6, time[at], times)
    return ScanLog(time=times, pose=pose[at], angles=angles, offset=offset,
                   ranges=np.array([list(m.ranges) for _, m in rows], dtype=np.float32),
                   max_range=float(lidar["max_range"]))


def load_any(path: str | Path) -> RunLog:
    """A run log from an .mcap (this module) or an .npz (:func:`pymunk_bot.outcomes.runlog.load_log`)."""
    if Path(path).suffix.lower() == ".mcap":
        return load_mcap(path)
    from pymunk_bot.outcomes.runlog import load_log

    return load_log(path)
