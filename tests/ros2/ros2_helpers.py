"""Reading a ROS 2 bag back with rosbags: an MCAP reader and CDR deserializer written
independently of the one that wrote it."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore


@dataclass
class Bag:
    profile: str
    types: dict[str, str] = field(default_factory=dict)  # topic -> message type
    durability: dict[str, str] = field(default_factory=dict)  # topic -> QoS durability
    messages: dict[str, list[tuple[int, Any]]] = field(default_factory=dict)  # (log time, msg)


def read_bag(path: Path) -> Bag:
    from mcap.reader import make_reader

    with open(path, "rb") as stream:
        profile = make_reader(stream).get_header().profile
    store = get_typestore(Stores.ROS2_HUMBLE)
    bag = Bag(profile)
    with Reader(path) as reader:
        for connection in reader.connections:
            bag.types[connection.topic] = connection.msgtype
            qos = connection.ext.offered_qos_profiles
            bag.durability[connection.topic] = qos[0].durability.name if qos else ""
            bag.messages[connection.topic] = []
        for connection, log_time, raw in reader.messages():
            bag.messages[connection.topic].append(
                (log_time, store.deserialize_cdr(raw, connection.msgtype)))
    return bag
