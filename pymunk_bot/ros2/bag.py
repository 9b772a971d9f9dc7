"""ROS 2 bags: ``run --log run.mcap --profile ros2`` and ``convert --profile ros2``.

The file is one MCAP in rosbag2's layout: the ``ros2`` profile, ``ros2msg`` schemas (the
message definitions of the standard packages, Humble), CDR-encoded messages, and each topic's
``offered_qos_profiles`` in its channel's metadata (the maps and ``/tf_static`` transient
local, so ``ros2 bag play`` latches them). It is written to a temporary file beside the target
and renamed onto it by :meth:`Ros2Bag.commit`; an error or Ctrl-C leaves nothing behind, and
a full disk is an OSError naming the target (an incomplete bag is removed).
"""
from __future__ import annotations

import os
import weakref
from pathlib import Path
from typing import Any

from pymunk_bot.foxglove.snapshot import geometry_of_log, snapshots_of_log
from pymunk_bot.outcomes.results import naming, temp_beside
from pymunk_bot.ros2.messages import LiveMessages, Outgoing, RosMessages, typestore
from pymunk_bot.ros2.names import latched, qos_yaml

PROFILE = "ros2"
CHUNK_SIZE = 4 * 1024 * 1024  # [bytes] uncompressed per chunk


class Ros2Bag:
    """An MCAP rosbag2 being written; nothing appears at ``path`` until :meth:`commit`."""

    def __init__(self, path: str | Path) -> None:
        from mcap.writer import CompressionType, Writer

        self.path = Path(path)
        self._tmp = temp_beside(self.path, suffix=".mcap.tmp")
        self._cleanup = weakref.finalize(self, _remove, self._tmp)
        self._stream = open(self._tmp, "wb")
        self._writer = Writer(self._stream, chunk_size=CHUNK_SIZE,
                              compression=CompressionType.ZSTD)
        self._writer.start(profile=PROFILE, library="pymunk-bot")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        self.messages_written = 0

    def write(self, message: Outgoing) -> None:
        """Serialize ``message`` to CDR and append it."""
        channel = self._channels.get(message.topic)
        if channel is None:
            channel = self._channel(message.topic, message.msgtype)
        sequence = self._sequence[message.topic] = self._sequence[message.topic] + 1
        data = typestore().serialize_cdr(message.msg, message.msgtype)
        self._writer.add_message(channel, log_time=message.log_time, data=bytes(data),
                                 publish_time=message.log_time, sequence=sequence)
        self.messages_written += 1

    def _channel(self, topic: str, msgtype: str) -> int:
        schema = self._schemas.get(msgtype)
        if schema is None:
            text, _ = typestore().generate_msgdef(msgtype, ros_version=2)
            schema = self._schemas[msgtype] = self._writer.register_schema(
                name=msgtype, encoding="ros2msg", data=text.encode())
        channel = self._channels[topic] = self._writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=schema,
            metadata={"offered_qos_profiles": qos_yaml(latched(topic, msgtype))})
        self._sequence[topic] = 0
        return channel

    def commit(self) -> None:
        """Finish the file (summary, indexes) and move it onto ``path``; OSError naming
        ``path`` if it cannot be written (then nothing is left behind)."""
        try:
            self._writer.finish()
            self._stream.close()
            os.replace(self._tmp, self.path)
        except OSError as exc:
            self.abort()
            raise naming(exc, self.path) from exc
        self._cleanup.detach()

    def abort(self) -> None:
        """Close and delete the unfinished file."""
        try:
            self._stream.close()
        except OSError:  # the buffered tail of a file being deleted: its loss changes nothing
            pass
        finally:
            self._cleanup()


class Ros2BagLogger:
    """A simulation observer writing a ROS 2 bag after every step: :meth:`attach`, run,
    :meth:`save` (or :meth:`abort`). Survives ``sim.reset()``: the bag then goes on from the
    reset (its clock starts again at zero)."""

    def __init__(self, path: str | Path, world_map: Any = None) -> None:
        self.path = Path(path)
        self.world_map = world_map  # the OccupancyGrid for /map, or None
        self.bag = Ros2Bag(path)
        self.steps = 0
        self._messages: LiveMessages | None = None
        self.failed: OSError | None = None  # a write that failed (a full disk): the run goes on

    def _write(self, messages) -> None:
        if self.failed is not None:
            return
        try:
            for message in messages:
                self.bag.write(message)
        except OSError as exc:  # the bag is lost, the run is not: save() reports it
            self.failed = naming(exc, self.path)
            self.bag.abort()

    def attach(self, sim) -> "Ros2BagLogger":
        """Start recording ``sim`` from its present state."""
        sim.attach(self)  # on_reset now, then every step
        return self

    def on_reset(self, sim) -> None:
        self._messages = LiveMessages(sim, self.world_map)
        self._write(self._messages.start(sim))

    def __call__(self, sim) -> None:
        if self._messages is None:
            raise RuntimeError("Ros2BagLogger: attach() it to the simulation first")
        self.steps += 1
        self._write(self._messages.step(sim))

    def save(self) -> None:
        """Finish the bag; OSError naming it if it could not be written (nothing is left)."""
        if self.failed is not None:
            raise self.failed
        self.bag.commit()

    def abort(self) -> None:
        self.bag.abort()


def write_bag(log, path: str | Path) -> int:
    """Write a :class:`~pymunk_bot.outcomes.runlog.RunLog` as a ROS 2 bag, atomically; returns the
    number of messages. ``/map`` is rasterised from the fixed shapes the log keeps. A log holds
    no plans, localizer estimates or IMU readings: those topics are absent, and ``map`` ->
    ``odom`` is the identity (odometry is the estimate)."""
    from pymunk_bot.ros2.worldmap import geometry_grid

    bag = Ros2Bag(path)
    try:
        snapshots = snapshots_of_log(log)
        geometry = geometry_of_log(log)
        messages = RosMessages(geometry, geometry_grid(geometry))
        for message in messages.start(next(snapshots)):
            bag.write(message)
        for snapshot in snapshots:
            for message in messages.messages(snapshot):
                bag.write(message)
        bag.commit()
    except BaseException:
        bag.abort()
        raise
    return bag.messages_written


def _remove(path: str) -> None:
    Path(path).unlink(missing_ok=True)
