"""Frame and topic names, and the small conversions every message needs.

Frames follow ROS conventions (REP-103/105): ``world`` is the fixed frame (x right, y up, z out
of the floor); each robot ``<name>`` has ``<name>/base_link`` at the centre of its body (x
forward) and ``<name>/lidar`` at its LiDAR mount. Times are simulated seconds since the start
of the run, written as nanoseconds (a timestamp of 0 is the run's first instant).
"""
from __future__ import annotations

import math

WORLD_FRAME = "world"
DEFAULT_HOST = "127.0.0.1"  # the live server listens on this machine only unless told otherwise
DEFAULT_PORT = 8765  # Foxglove's usual WebSocket port
NS_PER_S = 1_000_000_000

# Topics shared by the whole run
TF_TOPIC = "/tf"  # foxglove.FrameTransforms: world -> robots -> their LiDAR mounts
SCENE_TOPIC = "/scene"  # foxglove.SceneUpdate: arena, obstacles, robots, goals
LOG_TOPIC = "/log"  # foxglove.Log: contacts, goals reached, controller status changes
OBSTACLES_TOPIC = "/obstacles/poses"  # JSON: poses of the movable obstacles, every step
METADATA_NAME = "pymunk_bot"  # MCAP metadata record holding the run's geometry (for replay)


def base_frame(robot: str) -> str:
    """The body frame of robot ``robot``."""
    return f"{robot}/base_link"


def lidar_frame(robot: str) -> str:
    """The LiDAR mount frame of robot ``robot``."""
    return f"{robot}/lidar"


def robot_topic(robot: str, what: str) -> str:
    """``/<robot>/<what>``: scan, ground_truth, odometry, localization, path, map, state."""
    return f"/{robot}/{what}"


def nanoseconds(t: float) -> int:
    """Simulated seconds -> integer nanoseconds (the MCAP log time)."""
    return int(round(t * NS_PER_S))


def yaw_quaternion(theta: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation by ``theta`` [rad] about z."""
    half = 0.5 * theta
    return 0.0, 0.0, math.sin(half), math.cos(half)


def quaternion_yaw(x: float, y: float, z: float, w: float) -> float:
    """The rotation about z [rad] of a quaternion (the inverse of :func:`yaw_quaternion`)."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
