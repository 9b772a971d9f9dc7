"""`run --foxglove`: a plain WebSocket client sees serverInfo, the channels and live data."""
from __future__ import annotations

import asyncio
import base64
import json
import socket
import struct

import foxglove
import numpy as np
import pytest
from builders import robot, scenario, wheels

from pymunk_bot import Simulation
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.foxglove.frames import quaternion_yaw
from pymunk_bot.foxglove.live import LiveServer, run_paced
from pymunk_bot.foxglove.publisher import Publisher, SimPublisher

websockets = pytest.importorskip("websockets")
# The SDK speaks the Foxglove WebSocket protocol under its current name, foxglove.sdk.v1
# (identical to foxglove.websocket.v1, which this SDK no longer accepts alone).
SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
MESSAGE_DATA = 0x01  # binary opcode of the protocol


def make_sim():
    return Simulation.from_dict(scenario(
        [robot([1.0, 1.0, 0.0], name="r1", controller=wheels(0.4, 0.5),
               lidar={"beams": 30, "max_range": 3.0, "rate": 10.0})], size=(4.0, 3.0)))


@pytest.fixture
def served():
    """A simulation published live on a free port of 127.0.0.1; stopped afterwards."""
    sim = make_sim()
    context = foxglove.Context()
    server = LiveServer(context, "127.0.0.1", 0)
    SimPublisher(Publisher(context)).attach(sim)
    yield sim, server
    server.stop()


def decoder(channel: dict):
    """A protobuf decoder for an advertised channel (its schema is a FileDescriptorSet)."""
    from mcap.records import Schema
    from mcap_protobuf.decoder import DecoderFactory

    schema = Schema(id=1, name=channel["schemaName"], encoding=channel["schemaEncoding"],
                    data=base64.b64decode(channel["schema"]))
    return DecoderFactory().decoder_for(channel["encoding"], schema)


async def watch(url: str, sim, topic: str):
    """Connect, read serverInfo and the advertised channels, subscribe to ``topic`` and step
    the simulation until a message arrives. Returns (serverInfo, channels, (log_time, msg))."""
    async with websockets.connect(url, subprotocols=SUBPROTOCOLS) as ws:
        info = json.loads(await asyncio.wait_for(ws.recv(), 5))
        channels: dict[str, dict] = {}
        while topic not in channels or "/r1/scan" not in channels:
            message = json.loads(await asyncio.wait_for(ws.recv(), 5))
            if message["op"] == "advertise":
                channels.update({c["topic"]: c for c in message["channels"]})
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": 7, "channelId": channels[topic]["id"]}]}))
        for _ in range(600):  # the subscription takes effect within a few steps
            sim.step()
            try:
                data = await asyncio.wait_for(ws.recv(), 0.01)
            except asyncio.TimeoutError:
                continue
            if isinstance(data, bytes) and data[0] == MESSAGE_DATA:
                subscription, log_time = struct.unpack_from("<IQ", data, 1)
                assert subscription == 7
                return info, channels, (log_time, decoder(channels[topic])(data[13:]))
        raise AssertionError("no message arrived")


def test_a_client_sees_server_info_channels_and_live_poses(served):
    sim, server = served
    info, channels, (log_time, pose) = asyncio.run(
        watch(f"ws://127.0.0.1:{server.port}", sim, "/r1/ground_truth"))
    assert info["op"] == "serverInfo" and info["name"] == "pymunk-bot"
    schemas = {topic: (c["schemaName"], c["encoding"]) for topic, c in channels.items()}
    assert schemas["/tf"] == ("foxglove.FrameTransforms", "protobuf")
    assert schemas["/r1/scan"] == ("foxglove.LaserScan", "protobuf")
    assert schemas["/r1/ground_truth"] == ("foxglove.PoseInFrame", "protobuf")
    assert schemas["/r1/state"] == ("pymunk_bot.RobotState", "json")
    # The message is the pose at the simulated time it carries.
    assert 0 < log_time <= round(sim.time * 1e9)
    replay = make_sim()
    replay.run(log_time / 1e9)
    q = pose.pose.orientation
    got = [pose.pose.position.x, pose.pose.position.y, quaternion_yaw(q.x, q.y, q.z, q.w)]
    assert np.allclose(got, replay.robots["r1"].pose, atol=1e-12)


def test_clients_coming_and_going_do_not_disturb_the_run(served):
    sim, server = served
    asyncio.run(watch(f"ws://127.0.0.1:{server.port}", sim, "/r1/scan"))  # then disconnects
    sim.run(1.0)
    alone = make_sim()
    alone.run(sim.time)
    assert np.array_equal(sim.robots["r1"].pose, alone.robots["r1"].pose)


def test_a_busy_port_is_bad_input():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(ScenarioError, match=f"cannot serve on 127.0.0.1:{port}.*in use"):
            LiveServer(foxglove.Context(), "127.0.0.1", port)


def test_headless_runs_are_paced_at_real_time_times_speed():
    sim = make_sim()
    now = [0.0]
    slept = []

    def sleep(seconds):
        slept.append(seconds)
        now[0] += seconds

    run_paced(sim, 1.0, speed=2.0, clock=lambda: now[0], sleep=sleep)
    assert sim.time == pytest.approx(1.0)
    assert now[0] == pytest.approx(0.5)  # 1 s simulated at 2x real time
