"""ROS messages <-> the JSON that rosbridge (and Foxglove's ``json`` client publishing) speaks.

Outgoing: a ``rosbags`` message becomes nested dicts keyed by field name, encoded with
``orjson`` (numpy arrays directly; a float32 array as the shortest decimals that read back to
the same float32s). JSON has no infinity: a ``+inf`` range (REP-117's "no return") or a NaN is
sent as ``null``, as rosbridge does, so that every JSON parser (JavaScript's included) reads it.

Incoming: only what clients may publish here, ``geometry_msgs/msg/Twist`` and
``geometry_msgs/msg/PoseStamped``. A missing field is 0 (rosbridge fills defaults the same
way); a field of the wrong kind is a :class:`BadMessage` naming its path.
"""
from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

import orjson


class BadMessage(ValueError):
    """A client's message that does not fit its type; the text names the field."""


def to_plain(msg: Any) -> Any:
    """A rosbags message (or any value inside one) as dicts and lists, arrays left as they
    are (:func:`dumps` encodes them)."""
    if isinstance(msg, list):
        return [to_plain(v) for v in msg]
    if hasattr(msg, "__dataclass_fields__"):
        return {f.name: to_plain(getattr(msg, f.name)) for f in fields(msg)
                if not f.name.startswith("__")}  # rosbags' __msgtype__ is no field of ROS's
    return msg


def dumps(value: Any) -> str:
    """JSON text of plain values and numpy arrays; non-finite floats become ``null``."""
    return orjson.dumps(value, option=orjson.OPT_SERIALIZE_NUMPY).decode()


def loads(text: str | bytes) -> Any:
    """Parse JSON text; ValueError (with the reason) if it is not JSON."""
    return orjson.loads(text)


def _number(data: dict, key: str, path: str) -> float:
    value = data.get(key, 0.0)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise BadMessage(f"{path}.{key} must be a number (got {type(value).__name__})")
    value = float(value)
    if not math.isfinite(value):
        raise BadMessage(f"{path}.{key} must be finite (got {value})")
    return value


def _object(data: Any, key: str, path: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise BadMessage(f"{path}.{key} must be an object (got {type(value).__name__})")
    return value


def _vector(data: dict, key: str, path: str) -> tuple[float, float, float]:
    inner = _object(data, key, path)
    x, y, z = (_number(inner, axis, f"{path}.{key}") for axis in "xyz")
    return x, y, z


def parse_twist(data: Any) -> tuple[float, float, float]:
    """(v forward [m/s], omega [rad/s], vy left [m/s]) of a geometry_msgs/msg/Twist."""
    if not isinstance(data, dict):
        raise BadMessage(f"msg must be an object (got {type(data).__name__})")
    linear, angular = _vector(data, "linear", "msg"), _vector(data, "angular", "msg")
    return linear[0], angular[2], linear[1]


def parse_pose_stamped(data: Any) -> tuple[float, float, str]:
    """(x [m], y [m], frame_id) of a geometry_msgs/msg/PoseStamped."""
    if not isinstance(data, dict):
        raise BadMessage(f"msg must be an object (got {type(data).__name__})")
    frame = _object(data, "header", "msg").get("frame_id", "")
    if not isinstance(frame, str):
        raise BadMessage("msg.header.frame_id must be a string")
    position = _object(_object(data, "pose", "msg"), "position", "msg.pose")
    where = "msg.pose.position"
    return _number(position, "x", where), _number(position, "y", where), frame
