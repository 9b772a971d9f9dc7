"""One Foxglove client cannot flood the server's stderr: the SDK's line per bad request is held
to a few lines per client per minute, and what was held back is counted."""
from __future__ import annotations

import asyncio
import json
import logging

import foxglove
import pytest

from pymunk_bot.foxglove.live import CLIENT_LINES, ClientLogLimit, LiveServer

websockets = pytest.importorskip("websockets")
SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]


def test_a_5000_entry_subscribe_prints_a_few_lines(capfd):
    server = LiveServer(foxglove.Context(), "127.0.0.1", 0)

    async def flood() -> None:
        async with websockets.connect(server.url, subprotocols=SUBPROTOCOLS) as ws:
            await asyncio.wait_for(ws.recv(), 5)  # serverInfo
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": i, "channelId": 10**6 + i} for i in range(5000)]}))
            await asyncio.sleep(0.5)

    try:
        asyncio.run(flood())
    finally:
        server.stop()
    lines = capfd.readouterr().err.strip().splitlines()
    assert 1 <= len(lines) <= CLIENT_LINES + 1, lines[:10]
    assert "unknown channel" in lines[0] and "held back" in lines[-1]
    assert logging.getLogger("foxglove").propagate  # the server's stop put logging back


def record(message: str) -> logging.LogRecord:
    return logging.LogRecord("foxglove.websocket", logging.ERROR, __file__, 1, message, (), None)


def test_each_client_has_its_own_allowance_and_held_lines_are_counted():
    now = [0.0]
    limit = ClientLogLimit(lines=2, window=10.0, clock=lambda: now[0])
    a = [limit.filter(record(f"Client 10.0.0.1:5 bad request {k}")) for k in range(50)]
    b = [limit.filter(record(f"Client 10.0.0.2:7 bad request {k}")) for k in range(3)]
    assert sum(a) == 3 and b == [True, True, True]
    now[0] = 11.0
    later = record("Client 10.0.0.1:5 bad request again")
    assert limit.filter(later) and "48 more lines about 10.0.0.1:5" in later.getMessage()
