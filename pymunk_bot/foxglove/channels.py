"""The channels of a run in one Foxglove context, created when first needed.

Foxglove's own schemas (protobuf, written by the SDK) carry the standard data; two JSON
channels carry what has no standard schema: each robot's state (speeds, commands, counters;
what the speed plot shows) and the movable obstacles' poses.
"""
from __future__ import annotations

import json
from typing import Any

import foxglove
from foxglove import channels as fc

ROBOT_STATE_SCHEMA = {
    "title": "pymunk_bot.RobotState",
    "description": "One robot's state after a simulation step (SI units).",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "simulated time [s]"},
        "pose": {"type": "array", "items": {"type": "number"},
                 "description": "ground truth [x m, y m, theta rad]"},
        "odometry": {"type": "array", "items": {"type": "number"},
                     "description": "odometry estimate [x m, y m, theta rad]"},
        "v": {"type": "number", "description": "true forward speed [m/s]"},
        "omega": {"type": "number", "description": "true yaw rate [rad/s]"},
        "velocity": {"type": "array", "items": {"type": "number"},
                     "description": "the robot's velocity as it reports it"},
        "command": {"type": ["array", "null"], "items": {"type": "number"},
                    "description": "commanded wheel speeds (left, right) [m/s]"},
        "wheel_speeds": {"type": ["array", "null"], "items": {"type": "number"},
                         "description": "wheel speeds (left, right) [m/s]"},
        "collisions": {"type": "integer", "description": "contact episodes so far"},
        "goal": {"type": ["array", "null"], "items": {"type": "number"},
                 "description": "goal position [m]"},
        "goal_tolerance": {"type": "number", "description": "[m]"},
        "goal_reached": {"type": "boolean"},
        "teleop": {"type": "boolean", "description": "commanded by hand"},
        "status": {"type": "string", "description": "the controller's status"},
    },
}
OBSTACLE_POSES_SCHEMA = {
    "title": "pymunk_bot.ObstaclePoses",
    "description": "Poses of the movable obstacles after a simulation step.",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "simulated time [s]"},
        "obstacles": {"type": "array", "items": {"type": "integer"},
                      "description": "index of each in the scenario's obstacle list"},
        "poses": {"type": "array", "items": {"type": "array", "items": {"type": "number"}},
                  "description": "[x m, y m, theta rad] of each"},
    },
}

_SDK_CHANNELS = {
    "FrameTransforms": fc.FrameTransformsChannel, "SceneUpdate": fc.SceneUpdateChannel,
    "Log": fc.LogChannel, "LaserScan": fc.LaserScanChannel, "PoseInFrame": fc.PoseInFrameChannel,
    "PosesInFrame": fc.PosesInFrameChannel, "Grid": fc.GridChannel,
}


class Channels:
    """Channels by topic in one :class:`foxglove.Context`, made on first use."""

    def __init__(self, context: foxglove.Context) -> None:
        self.context = context
        self._channels: dict[str, Any] = {}

    def get(self, topic: str, kind: str | dict) -> Any:
        """The channel for ``topic``; ``kind`` is a Foxglove schema name (without the
        ``foxglove.`` prefix) or a JSON schema dict."""
        channel = self._channels.get(topic)
        if channel is None:
            if isinstance(kind, dict):
                schema = foxglove.Schema(name=kind["title"], encoding="jsonschema",
                                         data=json.dumps(kind).encode())
                channel = foxglove.Channel(topic, schema=schema, message_encoding="json",
                                           context=self.context)
            else:
                channel = _SDK_CHANNELS[kind](topic, context=self.context)
            self._channels[topic] = channel
        return channel

    def wanted(self, topic: str, kind: str | dict) -> Any:
        """The channel if anyone listens (a file or a subscribed client), else None, so
        nobody pays for messages that no one receives."""
        channel = self.get(topic, kind)
        return channel if channel.has_sinks() else None

    def close(self) -> None:
        """Unadvertise every channel."""
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()
