"""Foxglove teleop: the live server offers clientPublish, and a client publishing a JSON Twist on
/cmd_vel (what Foxglove's Teleop panel sends) drives the robot until the watchdog stops it."""
from __future__ import annotations

import asyncio
import json
import struct

import pytest
from builders import robot, scenario

from pymunk_bot import Simulation

foxglove = pytest.importorskip("foxglove")
websockets = pytest.importorskip("websockets")

SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
CLIENT_MESSAGE_DATA = 0x01  # binary opcode, client -> server


@pytest.fixture
def served():
    from pymunk_bot.foxglove.live import LiveServer
    from pymunk_bot.foxglove.publisher import Publisher, SimPublisher
    from pymunk_bot.foxglove.teleop import attach_teleop

    sim = Simulation.from_dict(scenario([robot([1.0, 1.0, 0.0], name="r1")], size=(6.0, 3.0),
                                        dt=1 / 50))
    lines: list[str] = []
    context = foxglove.Context()
    server = LiveServer(context, "127.0.0.1", 0, teleop=attach_teleop(sim, 0.5, lines.append))
    SimPublisher(Publisher(context)).attach(sim)
    yield sim, server, lines
    server.stop()


async def teleop(url: str, sim, twist: dict, steps: int) -> dict:
    """Advertise /cmd_vel as Foxglove's Teleop panel does, publish ``twist`` every step for
    ``steps`` steps, and some junk; returns the serverInfo."""
    async with websockets.connect(url, subprotocols=SUBPROTOCOLS) as ws:
        info = json.loads(await asyncio.wait_for(ws.recv(), 5))
        await ws.send(json.dumps({"op": "advertise", "channels": [
            {"id": 3, "topic": "/cmd_vel", "encoding": "json",
             "schemaName": "geometry_msgs/msg/Twist"},
            {"id": 4, "topic": "/elsewhere", "encoding": "json",
             "schemaName": "std_msgs/String"}]}))
        await asyncio.sleep(0.1)
        for k in range(steps):
            await ws.send(struct.pack("<BI", CLIENT_MESSAGE_DATA, 3) + json.dumps(twist).encode())
            if k == 0:
                await ws.send(struct.pack("<BI", CLIENT_MESSAGE_DATA, 3) + b"{oops")
            await asyncio.sleep(0.005)
            sim.step()
        return info


def test_teleop_panel_drives_the_robot_and_the_watchdog_stops_it(served):
    sim, server, lines = served
    twist = {"linear": {"x": 0.25, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    info = asyncio.run(teleop(server.url, sim, twist, 100))
    assert "clientPublish" in info["capabilities"] and "json" in info["supportedEncodings"]
    r1 = sim.robots["r1"]
    assert r1.overridden and r1.velocity[0] == pytest.approx(0.25, abs=0.01)
    assert any("advertised /elsewhere" in line for line in lines)
    assert any("/cmd_vel: malformed JSON" in line for line in lines)
    import time

    time.sleep(0.6)  # the watchdog's 0.5 s of silence
    for _ in range(50):
        sim.step()
    assert not r1.overridden and abs(r1.velocity[0]) < 1e-3
