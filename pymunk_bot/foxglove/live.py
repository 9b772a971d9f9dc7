"""``run --foxglove``: the Foxglove SDK's WebSocket server, fed while the simulation runs.

The server binds to 127.0.0.1 unless told otherwise. Clients connect, subscribe and leave
whenever they like: the SDK buffers per client and drops a slow client's oldest messages, so
no client can stall the simulation. Headless runs are paced at real time x ``speed`` so a
viewer sees motion as it happens.
"""
from __future__ import annotations

import math
import time
from typing import Any

import foxglove

from ..errors import ScenarioError
from .frames import DEFAULT_HOST, DEFAULT_PORT
MAX_SPEED = 1000.0  # x real time
MAX_LAG = 0.25  # [s] wall: further behind than this, the pace restarts instead of rushing


def check_speed(speed: float) -> float:
    """``speed`` if it is a usable real-time factor, else a one-line ScenarioError."""
    if not (math.isfinite(speed) and 0 < speed <= MAX_SPEED):
        raise ScenarioError("--speed", "", f"must be > 0 and <= {MAX_SPEED:g} (got {speed:g})")
    return speed


class LiveServer:
    """A running Foxglove WebSocket server on ``context``; :meth:`stop` it when done."""

    def __init__(self, context: foxglove.Context, host: str = DEFAULT_HOST,
                 port: int = DEFAULT_PORT, name: str = "pymunk-bot") -> None:
        if not 0 <= port <= 65535:
            raise ScenarioError("--port", "", f"must be 0..65535 (got {port})")
        try:
            self.server: Any = foxglove.start_server(name=name, host=host, port=port, context=context)
        except (RuntimeError, OSError, ValueError) as exc:
            reason = str(exc).split(": ", 1)[-1]  # drop the SDK's "FoxgloveError: " prefix
            raise ScenarioError("--foxglove", "", f"cannot serve on {host}:{port}: {reason}"
                                f"{' (try another --port)' if 'in use' in reason else ''}") from None
        self.host = host
        self.port = self.server.port  # the bound one (port 0 picks a free port)

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def stop(self) -> None:
        """Disconnect every client and free the port (safe to call twice)."""
        if self.server is not None:
            self.server.stop()
            self.server = None


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
