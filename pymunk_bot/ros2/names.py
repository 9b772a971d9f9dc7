"""Topic names, frame names and QoS of the ROS 2 side (the table in docs/ros2.md).

One robot: its topics at the root (``/scan``, ``/odom``) and frames without a prefix
(``odom``, ``base_link``, ``laser``). Several robots: each robot's topics under ``/<robot>/``
and its frames prefixed ``<robot>/``, so every robot hangs off the one shared ``map`` frame on
the one ``/tf`` tree (REP-105).
"""
from __future__ import annotations

from dataclasses import dataclass

MAP_FRAME = "map"
TF_TOPIC = "/tf"
TF_STATIC_TOPIC = "/tf_static"
CLOCK_TOPIC = "/clock"
MAP_TOPIC = "/map"
OBSTACLES_TOPIC = "/obstacles"
DEFAULT_PORT = 9090  # rosbridge's usual port
DEFAULT_COMMAND_TIMEOUT = 0.5  # [s] wall: a /cmd_vel older than this gives the robot back

# Message types by the short names used here.
TYPES = {
    "scan": "sensor_msgs/msg/LaserScan",
    "odom": "nav_msgs/msg/Odometry",
    "ground_truth": "nav_msgs/msg/Odometry",
    "imu": "sensor_msgs/msg/Imu",
    "pose": "geometry_msgs/msg/PoseWithCovarianceStamped",
    "plan": "nav_msgs/msg/Path",
    "cmd_vel": "geometry_msgs/msg/Twist",
    "goal_pose": "geometry_msgs/msg/PoseStamped",
    "tf": "tf2_msgs/msg/TFMessage",
    "clock": "rosgraph_msgs/msg/Clock",
    "map": "nav_msgs/msg/OccupancyGrid",
    "slam_map": "nav_msgs/msg/OccupancyGrid",
    "markers": "visualization_msgs/msg/MarkerArray",
}


@dataclass(frozen=True)
class RobotNames:
    """The topics and frames of one robot (``alone``: the only robot of the run)."""

    robot: str
    alone: bool

    def topic(self, what: str) -> str:
        """``/<what>`` for a robot alone, else ``/<robot>/<what>``."""
        return f"/{what}" if self.alone else f"/{self.robot}/{what}"

    def frame(self, what: str) -> str:
        """``<what>`` for a robot alone, else ``<robot>/<what>``."""
        return what if self.alone else f"{self.robot}/{what}"

    @property
    def odom(self) -> str:
        return self.frame("odom")

    @property
    def base_link(self) -> str:
        return self.frame("base_link")

    @property
    def laser(self) -> str:
        return self.frame("laser")


def robot_names(robots: list[str]) -> dict[str, RobotNames]:
    """Names for every robot of a run, by robot."""
    alone = len(robots) == 1
    return {name: RobotNames(name, alone) for name in robots}


def qos_yaml(latched: bool) -> str:
    """rosbag2's ``offered_qos_profiles`` (Humble's integer form) for one publisher: reliable,
    keep-last; ``latched``: transient local, so a late subscriber still gets the last message."""
    never = "    sec: 2147483647\n    nsec: 4294967295\n"  # rmw's "infinite" duration
    return ("- history: 1\n  depth: 1\n" if latched else "- history: 1\n  depth: 10\n") + (
        "  reliability: 1\n"
        f"  durability: {1 if latched else 2}\n"
        f"  deadline:\n{never}  lifespan:\n{never}"
        "  liveliness: 1\n"
        f"  liveliness_lease_duration:\n{never}"
        "  avoid_ros_namespace_conventions: false\n")


def latched(topic: str, msgtype: str) -> bool:
    """Whether a topic is latched (transient local): ``/tf_static`` and every map."""
    return topic == TF_STATIC_TOPIC or msgtype == TYPES["map"]


def command_topics(robots: list[str]) -> dict[str, tuple[str, str]]:
    """Topics clients publish on -> (robot, "cmd_vel" or "goal_pose"): ``/<robot>/...``
    always, and the root topics too when the run has one robot."""
    topics = {}
    for name, names in robot_names(robots).items():
        for what in ("cmd_vel", "goal_pose"):
            topics[names.topic(what)] = (name, what)
            topics[f"/{name}/{what}"] = (name, what)
    return topics
