"""Foxglove teleop: the live server accepts client publishing (the protocol's
``clientPublish`` capability), so Foxglove's Teleop panel drives a robot through ``/cmd_vel``
and a Publish panel sends it to a ``/goal_pose``.

Clients publish JSON (the only encoding the server offers): ``geometry_msgs/msg/Twist`` on
``/cmd_vel`` (``/<robot>/cmd_vel`` with several robots, or any robot by name) and
``geometry_msgs/msg/PoseStamped`` on ``/goal_pose``. Commands go through the same
:class:`~pymunk_bot.ros2.commands.CommandInbox` as rosbridge's, with its watchdog. The SDK
calls the listener from its own thread; a bad message is one line in the log (at most
``LOG_LINES_PER_S`` a second), never an exception.
"""
from __future__ import annotations

import time
from typing import Any, Callable

from pymunk_bot.ros2.commands import CommandInbox, command_of
from pymunk_bot.ros2.jsonmsg import BadMessage, loads
from pymunk_bot.ros2.names import command_topics

ENCODINGS = ["json"]
LOG_LINES_PER_S = 10


def attach_teleop(sim, timeout: float | None = None,
                  report: Callable[[str], None] = print) -> "TeleopListener":
    """A listener driving ``sim``'s robots, its command inbox attached to ``sim``
    (``timeout``: the watchdog's [s], default 0.5)."""
    from pymunk_bot.ros2.names import DEFAULT_COMMAND_TIMEOUT

    inbox = CommandInbox(DEFAULT_COMMAND_TIMEOUT if timeout is None else timeout,
                         report=report).attach(sim)
    return TeleopListener(inbox, list(sim.robots), report)


class TeleopListener:
    """A :class:`foxglove.websocket.ServerListener` turning client messages into commands."""

    def __init__(self, inbox: CommandInbox, robots: list[str],
                 report: Callable[[str], None] = print) -> None:
        self.inbox = inbox
        self.topics = command_topics(robots)
        self.report = report
        self._channels: dict[tuple[int, int], Any] = {}  # (client, channel) -> ClientChannel
        self._window, self._logged = 0.0, 0

    def on_client_advertise(self, client, channel) -> None:
        self._channels[(client.id, channel.id)] = channel
        if channel.topic not in self.topics:
            self._log(f"client {client.id} advertised {channel.topic}: only "
                      f"{', '.join(sorted(self.topics))} drive the simulation")

    def on_client_unadvertise(self, client, client_channel_id: int) -> None:
        self._channels.pop((client.id, client_channel_id), None)

    def on_message_data(self, client, client_channel_id: int, data: bytes) -> None:
        channel = self._channels.get((client.id, client_channel_id))
        if channel is None or channel.topic not in self.topics:
            return  # told once, when it was advertised
        robot, what = self.topics[channel.topic]
        try:
            if channel.encoding != "json":
                raise BadMessage(f"encoding {channel.encoding!r} (this server takes json)")
            try:
                message = loads(data)
            except ValueError as exc:
                raise BadMessage(f"malformed JSON ({exc})") from None
            accepted = self.inbox.put(command_of(robot, what, message))
            if not accepted:
                raise BadMessage("too many commands waiting; dropped")
        except BadMessage as exc:
            self._log(f"client {client.id} on {channel.topic}: {exc}")

    def _log(self, line: str) -> None:
        now = time.monotonic()
        if now - self._window >= 1.0:
            self._window, self._logged = now, 0
        if self._logged < LOG_LINES_PER_S:
            self._logged += 1
            self.report(f"foxglove: {line}")
