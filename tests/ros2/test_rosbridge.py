"""`run --rosbridge`: roslibpy (a real rosbridge client) on 127.0.0.1 sees the run, drives a
robot through /cmd_vel and sends it goals; bad clients are answered and logged, never obeyed."""
from __future__ import annotations

import asyncio
import json
import threading
import time

import pytest
from builders import robot, scenario

from pymunk_bot import Simulation
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.foxglove.live import run_paced
from pymunk_bot.ros2.bridge import serve_sim
from pymunk_bot.ros2.commands import CommandInbox
from pymunk_bot.ros2.worldmap import world_grid
from bounds import HANG_GUARD

roslibpy = pytest.importorskip("roslibpy")
websockets = pytest.importorskip("websockets")


def make_sim(controller=None, beams: int = 90, robots: int = 1) -> Simulation:
    """Robots in a 6 x 3 m room; with a controller, each starts on its (reached) task goal."""
    goal = {} if controller is None else {"goal": {"position": [1.0, 1.5], "tolerance": 0.2}}
    return Simulation.from_dict(scenario(
        [robot([1.0 + 2.0 * k, 1.5, 0.0], name=f"r{k + 1}", controller=controller, **goal,
               lidar={"beams": beams, "max_range": 4.0, "rate": 10.0})
         for k in range(robots)], size=(6.0, 3.0), dt=1 / 50))


class Served:
    """A simulation served over rosbridge on a free port, run paced in a thread."""

    def __init__(self, sim: Simulation, timeout: float = 0.5) -> None:
        self.sim = sim
        self.lines: list[str] = []
        inbox = CommandInbox(timeout, report=self.lines.append)
        self.server = serve_sim(sim, "127.0.0.1", 0, inbox, world_grid(sim.config),
                                report=self.lines.append)
        self.clients: list = []
        self.thread: threading.Thread | None = None

    def client(self):
        ros = roslibpy.Ros(host="127.0.0.1", port=self.server.port)
        ros.run(timeout=60)  # connecting: a hang guard, ample on a loaded machine
        self.clients.append(ros)
        return ros

    def run(self, duration: float, speed: float = 1.0) -> None:
        self.thread = threading.Thread(target=run_paced, args=(self.sim, duration, speed))
        self.thread.start()

    def wait(self) -> None:
        assert self.thread is not None
        self.thread.join(30)
        time.sleep(0.1)  # the last messages are on their way

    def stop(self) -> None:
        if self.thread is not None:
            self.thread.join(30)
        for ros in self.clients:
            ros.close()
        self.server.stop()


@pytest.fixture
def serve():
    made: list[Served] = []

    def start(sim: Simulation, timeout: float = 0.5) -> Served:
        made.append(Served(sim, timeout))
        return made[-1]

    yield start
    for served in made:
        served.stop()


def test_scans_arrive_at_the_lidar_rate_and_services_answer(serve):
    served = serve(make_sim())
    ros = served.client()
    scans, maps = [], []
    roslibpy.Topic(ros, "/scan", "sensor_msgs/msg/LaserScan").subscribe(scans.append)
    roslibpy.Topic(ros, "/map", "nav_msgs/msg/OccupancyGrid").subscribe(maps.append)
    assert set(ros.get_topics()) >= {"/scan", "/odom", "/tf", "/tf_static", "/map", "/clock",
                                     "/ground_truth", "/cmd_vel", "/goal_pose"}
    assert ros.get_topic_type("/scan") == "sensor_msgs/msg/LaserScan"
    time.sleep(0.2)  # the subscriptions are in
    started = time.perf_counter()
    served.run(1.5)
    served.wait()
    wall = time.perf_counter() - started
    stamps = [s["header"]["stamp"]["sec"] + 1e-9 * s["header"]["stamp"]["nanosec"] for s in scans]
    # Every scan of the 1.5 s arrives, paced: never faster than 10 Hz of wall time (a loaded
    # machine may only make the pace slower, so that side is not bounded).
    assert len(scans) >= 14 and len(scans) / wall < 12.0
    assert all(abs(b - a - 0.1) < 1e-6 for a, b in zip(stamps, stamps[1:]))  # and in sim time
    assert len(scans[0]["ranges"]) == 90 and None in scans[0]["ranges"]  # +inf -> null in JSON
    assert len(maps) == 1 and maps[0]["info"]["width"] > 0  # latched: sent on subscribing
    answer = roslibpy.Service(ros, "/rosapi/get_time", "rosapi/GetTime").call(
        roslibpy.ServiceRequest({}), timeout=60)
    assert abs(answer["time"]["sec"] + 1e-9 * answer["time"]["nanosec"] - 1.5) < 1e-6
    answer = roslibpy.Service(ros, "/rosapi/topics_and_raw_types", "rosapi/TopicsAndRawTypes").call(
        roslibpy.ServiceRequest({}), timeout=60)
    scan = answer["typedefs_full_text"][answer["topics"].index("/scan")]
    assert "float32[] ranges" in scan and "MSG: std_msgs/Header" in scan


def test_cmd_vel_drives_the_robot_and_the_watchdog_stops_it(serve):
    served = serve(make_sim())
    ros = served.client()
    truth = []
    roslibpy.Topic(ros, "/ground_truth", "nav_msgs/msg/Odometry").subscribe(truth.append)
    cmd = roslibpy.Topic(ros, "/cmd_vel", "geometry_msgs/msg/Twist")
    cmd.advertise()
    served.run(2.5)
    twist = roslibpy.Message({"linear": {"x": 0.3, "y": 0.0, "z": 0.0},
                              "angular": {"x": 0.0, "y": 0.0, "z": 0.4}})
    for _ in range(12):  # 1.2 s of commands at 10 Hz, then silence
        cmd.publish(twist)
        time.sleep(0.1)
    moving = list(truth)[-1]["twist"]["twist"]
    served.wait()
    # within one control period of the command (the drive's acceleration limit is long done)
    assert moving["linear"]["x"] == pytest.approx(0.3, abs=0.02)
    assert moving["angular"]["z"] == pytest.approx(0.4, abs=0.03)
    stopped = truth[-1]["twist"]["twist"]
    assert abs(stopped["linear"]["x"]) < 1e-3 and abs(stopped["angular"]["z"]) < 1e-3
    assert any("driven by /cmd_vel" in line for line in served.lines)
    assert any("no /cmd_vel for 0.5 s" in line for line in served.lines)
    assert not served.sim.robots["r1"].overridden  # given back to its controller


def test_a_goal_on_goal_pose_is_reached(serve):
    served = serve(make_sim(controller={"type": "go_to_goal"}))
    ros = served.client()
    truth = []
    roslibpy.Topic(ros, "/ground_truth", "nav_msgs/msg/Odometry").subscribe(truth.append)
    goal = roslibpy.Topic(ros, "/goal_pose", "geometry_msgs/msg/PoseStamped")
    goal.publish(roslibpy.Message({"header": {"frame_id": "map"},
                                   "pose": {"position": {"x": 4.5, "y": 2.0, "z": 0.0},
                                            "orientation": {"w": 1.0}}}))
    time.sleep(0.2)
    served.run(12.0, speed=8.0)
    served.wait()
    end = truth[-1]["pose"]["pose"]["position"]
    assert (end["x"] - 4.5) ** 2 + (end["y"] - 2.0) ** 2 < 0.2 ** 2


def test_ten_clients_keep_up_with_a_360_beam_scan(serve):
    served = serve(make_sim(beams=360))
    counts = []
    for _ in range(10):
        got: list = []
        counts.append(got)
        roslibpy.Topic(served.client(), "/scan", "sensor_msgs/msg/LaserScan").subscribe(
            lambda m, got=got: got.append(len(m["ranges"])))
    time.sleep(0.3)
    served.run(1.0)
    served.wait()
    assert all(len(got) >= 10 and set(got) == {360} for got in counts)


async def _bad_client(url: str) -> list[dict]:
    """A client that gets everything wrong, then floods, then leaves mid-stream."""
    async with websockets.connect(url, close_timeout=0.2) as ws:
        for text in ("{not json", "[" * 100_000, "[1, 2]", json.dumps({"op": "dance"}),
                     json.dumps({"op": "subscribe", "topic": "/scan", "type": "std_msgs/String"}),
                     json.dumps({"op": "subscribe", "topic": "/nope"}),
                     json.dumps({"op": "publish", "topic": "/cmd_vel",
                                 "msg": {"linear": {"x": "fast"}}}),
                     json.dumps({"op": "advertise", "topic": "/cmd_vel",
                                 "type": "std_msgs/String"}),
                     json.dumps({"op": "call_service", "service": "/nope", "id": "c1"})):
            await ws.send(text)
        replies = [json.loads(await asyncio.wait_for(ws.recv(), 5)) for _ in range(10)]
        await ws.send(json.dumps({"op": "subscribe", "topic": "/clock"}))  # and never reads
        for _ in range(2000):  # a flood of commands
            await ws.send(json.dumps({"op": "publish", "topic": "/cmd_vel",
                                      "msg": {"linear": {"x": 0.1}}}))
        await asyncio.sleep(0.5)  # the server reads on; then this client leaves mid-stream
    return replies


def test_bad_requests_are_answered_logged_and_the_run_goes_on(serve):
    served = serve(make_sim())
    ros = served.client()  # a good client beside the bad one
    clock = []
    roslibpy.Topic(ros, "/clock", "rosgraph_msgs/msg/Clock").subscribe(clock.append)
    served.run(1.5)
    replies = asyncio.run(_bad_client(served.server.url))
    served.wait()
    errors = [r["msg"] for r in replies if r["op"] == "status"]
    assert len(errors) == 9 and all(r["level"] == "error" for r in replies if r["op"] == "status")
    for expected in ("malformed JSON", "depth limit exceeded", "must be a JSON object",
                     "unknown op 'dance'",
                     "is sensor_msgs/msg/LaserScan, not std_msgs/String", "no topic /nope",
                     "msg.linear.x must be a number", "no service /nope"):
        assert any(expected in e for e in errors), expected
    assert {"op": "service_response", "service": "/nope", "result": False} .items() <= next(
        r for r in replies if r["op"] == "service_response").items()
    logged = [line for line in served.lines if line.startswith("rosbridge: client")]
    assert any("flooding" in line for line in logged)
    assert any("msg.linear.x must be a number" in line for line in logged)
    assert len(logged) <= 12  # one line each, then rate-limited
    assert served.sim.time == pytest.approx(1.5)
    assert len(clock) > 60  # the good client was served throughout


def test_watchdog_releases_only_after_the_timeout():
    sim = make_sim(controller={"type": "go_to_goal"})
    now = [0.0]
    lines: list[str] = []
    inbox = CommandInbox(0.5, clock=lambda: now[0], report=lines.append).attach(sim)
    from pymunk_bot.ros2.commands import Drive

    inbox.put(Drive("r1", 0.2, 0.0))
    sim.step()
    assert sim.robots["r1"].overridden and inbox.driven == ["r1"]
    now[0] = 0.5
    sim.step()
    assert sim.robots["r1"].overridden
    now[0] = 0.51
    sim.step()
    assert not sim.robots["r1"].overridden and inbox.driven == []
    assert lines[-1] == "r1: no /cmd_vel for 0.5 s: stopped, back to its controller"


def test_a_busy_port_is_one_clear_error(serve):
    served = serve(make_sim())
    with pytest.raises(ScenarioError, match=r"cannot serve on 127.0.0.1:\d+: .*try another --port"):
        serve_sim(make_sim(), "127.0.0.1", served.server.port)


def test_several_robots_are_namespaced(serve):
    served = serve(make_sim(robots=2))
    ros = served.client()
    topics = set(ros.get_topics())
    assert {"/r1/scan", "/r2/scan", "/r1/cmd_vel", "/r2/odom", "/tf", "/map"} <= topics
    assert "/scan" not in topics and "/cmd_vel" not in topics
    frames = []
    roslibpy.Topic(ros, "/tf", "tf2_msgs/msg/TFMessage").subscribe(
        lambda m: frames.append({t["child_frame_id"] for t in m["transforms"]}))
    time.sleep(0.2)
    served.run(0.3)
    served.wait()
    assert frames[-1] == {"r1/odom", "r1/base_link", "r2/odom", "r2/base_link"}


EXIT_SCRIPT = """
import roslibpy
from pymunk_bot import Simulation
from pymunk_bot.ros2.bridge import serve_sim
sim = Simulation.from_file("default")  # a module-level run, kept until the interpreter exits
server = serve_sim(sim, port=0, report=lambda line: None)
ros = roslibpy.Ros(host="127.0.0.1", port=server.port)
ros.run(timeout=60)
roslibpy.Topic(ros, "/odom", "nav_msgs/msg/Odometry").subscribe(lambda message: None)
sim.run(0.5)
ros.terminate()
server.stop()
print("stopped")
"""


def test_a_script_that_keeps_its_run_after_stopping_the_server_exits_cleanly():
    # A served run that outlives its server used to crash the interpreter's teardown (a pymunk
    # Space freed after cffi had gone, exit status -11): the server now lets go of the run.
    import subprocess
    import sys
    done = subprocess.run([sys.executable, "-c", EXIT_SCRIPT], capture_output=True, text=True,
                          timeout=HANG_GUARD)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().endswith("stopped")
