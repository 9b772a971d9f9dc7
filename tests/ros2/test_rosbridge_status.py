"""rosbridge always answers: a request it cannot take gets a ``status`` message (rosbridge v2:
op, level, msg, id) and the connection stays; a command the robot refuses after the step
is told to the client that sent it; a lateral /cmd_vel on a diff drive is obeyed without its
lateral part, with one warning; a client flooding bad requests gets bounded status traffic."""
from __future__ import annotations

import asyncio
import json

import pytest
from test_rosbridge import make_sim, serve  # noqa: F401  (serve: the fixture)

websockets = pytest.importorskip("websockets")


async def _session(url: str, requests: list[dict | str], listen: float,
                   between: float = 0.0) -> list[dict]:
    """Send ``requests`` (``between`` s apart), then read for ``listen`` s: every reply that is
    not a topic message."""
    replies: list[dict] = []
    async with websockets.connect(url, close_timeout=0.2) as ws:
        async def read() -> None:
            async for text in ws:
                reply = json.loads(text)
                if reply.get("op") != "publish":
                    replies.append(reply)

        reader = asyncio.create_task(read())
        for request in requests:
            await ws.send(request if isinstance(request, str) else json.dumps(request))
            if between:
                await asyncio.sleep(between)
        await asyncio.sleep(listen)
        reader.cancel()
    return replies


def statuses(replies: list[dict], level: str | None = None) -> list[dict]:
    return [r for r in replies if r["op"] == "status" and level in (None, r["level"])]


def test_an_id_that_is_a_list_or_an_object_is_answered_and_the_connection_stays(serve):
    served = serve(make_sim())
    version = {"op": "call_service", "service": "/rosapi/get_ros_version", "id": "v1"}
    replies = asyncio.run(_session(served.server.url, [
        {"op": "subscribe", "topic": "/clock", "id": [1, 2]},
        {"op": "call_service", "service": "/rosapi/get_ros_version", "id": {"n": 1}},
        version], listen=1.0))
    errors = statuses(replies, "error")
    assert len(errors) == 2 and all("'id' must be a string or a number" in e["msg"]
                                    for e in errors), replies
    assert "list" in errors[0]["msg"] and "dict" in errors[1]["msg"]
    answered = [r for r in replies if r["op"] == "service_response" and r.get("id") == "v1"]
    assert answered and answered[0]["values"]["version"] == 2  # the connection went on
    assert not any(line for line in served.lines if "Traceback" in line or "1011" in line)


def test_a_goal_outside_the_arena_and_a_wheel_speed_overflow_are_told_to_the_client(serve):
    served = serve(make_sim(controller={"type": "go_to_goal"}))
    served.run(1.5)
    replies = asyncio.run(_session(served.server.url, [
        {"op": "publish", "topic": "/goal_pose", "id": "far",
         "msg": {"header": {"frame_id": "map"}, "pose": {"position": {"x": 100.0, "y": 100.0}}}},
        {"op": "publish", "topic": "/cmd_vel", "id": "huge",
         "msg": {"linear": {"x": 1.7e308}, "angular": {"z": -1.7e308}}}], listen=0.8))
    served.wait()
    errors = {e.get("id"): e["msg"] for e in statuses(replies, "error")}
    assert "outside the arena" in errors.get("far", ""), replies
    assert "wheel speeds must be finite" in errors.get("huge", ""), replies
    assert any("outside the arena" in line for line in served.lines)  # and in the server's log


def test_a_lateral_cmd_vel_on_a_diff_drive_is_driven_without_it_with_one_warning(serve):
    served = serve(make_sim())
    served.run(2.0)
    twist = {"op": "publish", "topic": "/cmd_vel",
             "msg": {"linear": {"x": 0.3, "y": 0.2}, "angular": {"z": 0.0}}}
    replies = asyncio.run(_session(served.server.url, [twist] * 10, listen=0.3, between=0.1))
    served.wait()
    warnings = statuses(replies, "warning")
    assert len(warnings) == 1 and "linear.y" in warnings[0]["msg"], replies
    assert "ignored" in warnings[0]["msg"] and not statuses(replies, "error")
    robot = served.sim.robots["r1"]
    assert robot.distance > 0.2  # it drove forward (about 1 s at 0.3 m/s)
    assert abs(robot.pose[1] - 1.5) < 0.01  # and never sideways


def test_a_client_flooding_bad_requests_gets_bounded_status_traffic(serve):
    served = serve(make_sim())
    flood = [json.dumps({"op": "dance", "id": f"d{k}"}) for k in range(400)]
    replies = asyncio.run(_session(served.server.url, flood, listen=1.5))
    told = statuses(replies)
    assert 1 <= len(told) <= 25, len(told)
    assert told[0]["level"] == "error" and "unknown op 'dance'" in told[0]["msg"]
