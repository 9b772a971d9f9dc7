"""``run --foxglove``: the Foxglove SDK's WebSocket server, fed while the simulation runs.

The server binds to 127.0.0.1 unless told otherwise. Clients connect, subscribe and leave
whenever they like: the SDK buffers per client and drops a slow client's oldest messages, so
no client can stall the simulation. Headless runs are paced at real time x ``speed`` so a
viewer sees motion as it happens. While a server runs, the SDK's log lines (the ``foxglove``
logger) go to stderr through :class:`ClientLogLimit`: a few per client per minute, so no client
can flood the terminal (one 5,000-entry subscribe to unknown channels was 5,000 lines).
"""
from __future__ import annotations

import logging
import math
import re
import time
from typing import Any

import foxglove

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.foxglove.frames import DEFAULT_HOST, DEFAULT_PORT
MAX_SPEED = 1000.0  # x real time
MAX_LAG = 0.25  # [s] wall: further behind than this, the pace restarts instead of rushing
# What one client can make the server print: the SDK logs a line per bad request (a 5,000-entry
# subscribe to unknown channels is 5,000 lines), so each client gets this many lines per window.
CLIENT_LINES = 5
CLIENT_WINDOW = 60.0  # [s] wall
_CLIENT = re.compile(r"[Cc]lient (\S+?):? ")


class ClientLogLimit(logging.Filter):
    """Lets through at most ``lines`` of the SDK's log lines per client per ``window`` seconds;
    the first one held back says so, and the next window starts by saying how many were."""

    def __init__(self, lines: int = CLIENT_LINES, window: float = CLIENT_WINDOW,
                 clock=time.monotonic) -> None:
        super().__init__()
        self.lines, self.window, self.clock = lines, window, clock
        self.seen: dict[str, tuple[float, int]] = {}  # client -> (window start [s], lines)

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        match = _CLIENT.search(message)
        client = match.group(1) if match else "the server"
        now = self.clock()
        start, count = self.seen.get(client, (now, 0))
        if now - start >= self.window:
            if count > self.lines:
                record.msg = (f"({count - self.lines} more lines about {client} were not shown) "
                              f"{message}")
                record.args = ()
            start, count = now, 0
        count += 1
        if len(self.seen) > 10_000:  # many short-lived clients: forget the oldest
            self.seen.pop(next(iter(self.seen)))
        self.seen[client] = (start, count)
        if count == self.lines + 1:
            record.msg = (f"{message} (further lines about {client} are held back for "
                          f"{self.window:g} s)")
            record.args = ()
        return count <= self.lines + 1


def check_speed(speed: float) -> float:
    """``speed`` if it is a usable real-time factor, else a one-line ScenarioError."""
    if not (math.isfinite(speed) and 0 < speed <= MAX_SPEED):
        raise ScenarioError("--speed", "", f"must be > 0 and <= {MAX_SPEED:g} (got {speed:g})")
    return speed


class LiveServer:
    """A running Foxglove WebSocket server on ``context``; :meth:`stop` it when done."""

    def __init__(self, context: foxglove.Context, host: str = DEFAULT_HOST,
                 port: int = DEFAULT_PORT, name: str = "pymunk-bot", teleop: Any = None) -> None:
        """``teleop``: a :class:`~.teleop.TeleopListener`; clients may then publish (JSON)."""
        if not 0 <= port <= 65535:
            raise ScenarioError("--port", "", f"must be 0..65535 (got {port})")
        publish: dict[str, Any] = {} if teleop is None else {
            "capabilities": [foxglove.Capability.ClientPublish], "server_listener": teleop,
            "supported_encodings": ["json"]}
        try:
            self.server: Any = foxglove.start_server(name=name, host=host, port=port, context=context,
                                                     **publish)
        except (RuntimeError, OSError, ValueError) as exc:
            reason = str(exc).split(": ", 1)[-1]  # drop the SDK's "FoxgloveError: " prefix
            raise ScenarioError("--foxglove", "", f"cannot serve on {host}:{port}: {reason}"
                                f"{' (try another --port)' if 'in use' in reason else ''}") from None
        self.host = host
        self.port = self.server.port  # the bound one (port 0 picks a free port)
        self._log = logging.getLogger("foxglove")  # where the SDK's Rust side logs
        self._handler = logging.StreamHandler()  # stderr, the message alone (as before)
        self._handler.setLevel(logging.WARNING)
        self._handler.addFilter(ClientLogLimit())
        self._propagate = self._log.propagate
        self._log.addHandler(self._handler)
        self._log.propagate = False

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def stop(self) -> None:
        """Disconnect every client and free the port (safe to call twice)."""
        if self.server is not None:
            self.server.stop()
            self.server = None
            self._log.removeHandler(self._handler)
            self._log.propagate = self._propagate


def run_paced(sim, duration: float, speed: float = 1.0, clock=time.perf_counter,
              sleep=time.sleep) -> None:
    """Step ``sim`` for ``duration`` simulated seconds at ``speed`` x real time."""
    steps = round(duration / sim.dt)
    period = sim.dt / speed  # [s] wall per step
    start = clock()
    for k in range(1, steps + 1):
        sim.step()
        ahead = start + k * period - clock()
        if ahead > 0:
            sleep(ahead)
        elif ahead < -MAX_LAG:  # the simulation is slower than asked: do not rush to catch up
            start = clock() - k * period
