"""The rosbridge v2 protocol, without the transport: what one client's request does.

Supported ops: ``advertise``, ``unadvertise``, ``publish`` (on ``/cmd_vel`` and
``/goal_pose``), ``subscribe`` (with ``throttle_rate``), ``unsubscribe``, ``set_level`` and
``call_service``
for the ``rosapi`` services that rosbridge clients ask for when they connect (topics, their
types and definitions, the time, services, nodes). A bad request gets a ``status`` reply at
level ``error`` (as rosbridge sends) and one line in the server's log; so does a command the
robot refuses when it is applied after the step (through ``ClientState.tell``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

from pymunk_bot.ros2.commands import CommandInbox, command_of
from pymunk_bot.ros2.jsonmsg import BadMessage, loads
from pymunk_bot.ros2.names import (CLOCK_TOPIC, MAP_TOPIC, OBSTACLES_TOPIC, TF_STATIC_TOPIC, TF_TOPIC, TYPES,
                    command_topics, robot_names)

NODE = "/pymunk_bot"
SERVICES = ("/rosapi/topics", "/rosapi/topics_and_raw_types", "/rosapi/topic_type",
            "/rosapi/get_time", "/rosapi/get_ros_version", "/rosapi/services", "/rosapi/nodes")
ROS_VERSION = {"version": 2, "distro": "humble"}  # the message definitions served are Humble's


class BadRequest(ValueError):
    """A request this server refuses; the text is the reason, for the client and the log."""


def same_type(a: str, b: str) -> bool:
    """ROS 1 style "pkg/Type" and ROS 2 style "pkg/msg/Type" name the same type."""
    return a.replace("/msg/", "/") == b.replace("/msg/", "/")


@dataclass(frozen=True)
class Catalog:
    """The topics of one run: what the simulation publishes and what clients may publish."""

    published: dict[str, str]  # topic -> message type
    commands: dict[str, tuple[str, str]]  # topic -> (robot, "cmd_vel" or "goal_pose")

    @classmethod
    def of_run(cls, meta: dict, world_map: bool, mapping: Sequence[str] = ()) -> "Catalog":
        """From a run's metadata (:func:`~pymunk_bot.foxglove.snapshot.geometry_of_sim`);
        ``mapping``: the robots that build a map."""
        robots = meta["robots"]
        names = robot_names([r["name"] for r in robots])
        published = {CLOCK_TOPIC: TYPES["clock"], TF_TOPIC: TYPES["tf"]}
        if any(r.get("lidar") for r in robots):
            published[TF_STATIC_TOPIC] = TYPES["tf"]
        if world_map:
            published[MAP_TOPIC] = TYPES["map"]
        if meta.get("movable"):
            published[OBSTACLES_TOPIC] = TYPES["markers"]
        for robot in robots:
            n = names[robot["name"]]
            kinds = ["odom", "ground_truth", "imu", "pose", "plan"]
            extra = (["scan"] if robot.get("lidar") else []) + (
                ["slam_map"] if robot["name"] in mapping else [])
            for what in extra + kinds:
                published[n.topic(what)] = TYPES[what]
        return cls(published, command_topics([r["name"] for r in robots]))

    @property
    def every_step(self) -> frozenset[str]:
        """The published topics that may carry a message after any step (all but the
        sensors' own, which follow their readings, and the latched ones)."""
        return frozenset(t for t, kind in self.published.items()
                         if kind not in (TYPES["scan"], TYPES["imu"]) and t != TF_STATIC_TOPIC
                         and t != MAP_TOPIC)

    def type_of(self, topic: str) -> str | None:
        if topic in self.published:
            return self.published[topic]
        command = self.commands.get(topic)
        return None if command is None else TYPES[command[1]]

    @property
    def topics(self) -> dict[str, str]:
        """Every topic and its type."""
        return {**self.published, **{t: TYPES[what] for t, (_, what) in self.commands.items()}}


@dataclass
class Subscription:
    throttle: float = 0.0  # [s] wall: at least this between two messages to this client
    last_sent: float = -1e18  # [s] wall
    ids: set = field(default_factory=set)  # the request ids that subscribed (unsubscribe by id)


def valid_id(value: Any) -> bool:
    """Whether ``value`` may be a request's ``id`` (rosbridge's are strings; numbers too)."""
    return value is None or isinstance(value, str) or (
        isinstance(value, (int, float)) and not isinstance(value, bool))


def _no_reply(level: str, message: str, request_id: Any) -> None:
    pass


@dataclass
class ClientState:
    """What one client has asked for; ``tell(level, message, id)`` sends it a ``status`` from
    any thread (the server sets it)."""

    name: str  # for the log: "client 3 (127.0.0.1:50312)"
    subscriptions: dict[str, Subscription] = field(default_factory=dict)
    advertised: dict[str, str] = field(default_factory=dict)  # topic -> type
    tell: Callable[[str, str, Any], None] = _no_reply


class Protocol:
    """Handles requests; ``send(client, reply)`` queues a JSON reply, ``time()`` is the
    simulated time [s], ``definitions(type)`` the full text of a message definition."""

    def __init__(self, catalog: Catalog, inbox: CommandInbox, time: Callable[[], float],
                 definitions: Callable[[str], str]) -> None:
        self.catalog = catalog
        self.inbox = inbox
        self.time = time
        self.definitions = definitions

    def handle(self, client: ClientState, text: str | bytes) -> list[dict]:
        """The replies to one request; raises :class:`BadRequest` for a bad one."""
        try:
            request = loads(text)
        except ValueError as exc:
            raise BadRequest(f"malformed JSON ({exc})") from None
        if not isinstance(request, dict):
            raise BadRequest("a request must be a JSON object")
        if not valid_id(request.get("id")):
            raise BadRequest(f"'id' must be a string or a number (got "
                             f"{type(request['id']).__name__})")
        op = request.get("op")
        handler = self.OPS.get(op) if isinstance(op, str) else None
        if handler is None:
            raise BadRequest(f"unknown op {op!r}" if op is not None else "request has no 'op'")
        return handler(self, client, request)

    # ------------------------------------------------------------------ ops
    def _subscribe(self, client: ClientState, request: dict) -> list[dict]:
        topic = _string(request, "topic")
        ours = self.catalog.published.get(topic)
        if ours is None:
            raise BadRequest(f"subscribe: no topic {topic} (see /rosapi/topics)")
        wanted = request.get("type")
        if wanted and (not isinstance(wanted, str) or not same_type(wanted, ours)):
            raise BadRequest(f"subscribe: {topic} is {ours}, not {wanted}")
        throttle = request.get("throttle_rate", 0) or 0
        if isinstance(throttle, bool) or not isinstance(throttle, (int, float)) or throttle < 0:
            raise BadRequest("subscribe: throttle_rate must be a number of milliseconds >= 0")
        subscription = client.subscriptions.setdefault(topic, Subscription())
        subscription.throttle = float(throttle) / 1000.0
        subscription.ids.add(request.get("id"))
        return []

    def _unsubscribe(self, client: ClientState, request: dict) -> list[dict]:
        topic = _string(request, "topic")
        subscription = client.subscriptions.get(topic)
        if subscription is None:
            raise BadRequest(f"unsubscribe: not subscribed to {topic}")
        subscription.ids.discard(request.get("id"))
        if not subscription.ids or request.get("id") is None:
            del client.subscriptions[topic]
        return []

    def _advertise(self, client: ClientState, request: dict) -> list[dict]:
        topic, kind = _string(request, "topic"), _string(request, "type")
        ours = self.catalog.type_of(topic)
        if topic not in self.catalog.commands:
            raise BadRequest(f"advertise: this simulator takes only "
                             f"{', '.join(sorted(self.catalog.commands))}, not {topic}")
        if ours is None or not same_type(kind, ours):
            raise BadRequest(f"advertise: {topic} is {ours}, not {kind}")
        client.advertised[topic] = kind
        return []

    def _unadvertise(self, client: ClientState, request: dict) -> list[dict]:
        client.advertised.pop(_string(request, "topic"), None)
        return []

    def _publish(self, client: ClientState, request: dict) -> list[dict]:
        topic = _string(request, "topic")
        command = self.catalog.commands.get(topic)
        if command is None:
            raise BadRequest(f"publish: this simulator takes only "
                             f"{', '.join(sorted(self.catalog.commands))}, not {topic}")
        request_id = request.get("id")

        def reply(level: str, message: str) -> None:  # a refusal after the step
            client.tell(level, message, request_id)

        try:
            accepted = self.inbox.put(command_of(*command, request.get("msg"), reply))
        except BadMessage as exc:
            raise BadRequest(f"publish on {topic}: {exc}") from None
        if not accepted:
            raise BadRequest(f"publish on {topic}: too many commands waiting; dropped")
        return []

    def _call_service(self, client: ClientState, request: dict) -> list[dict]:
        service = _string(request, "service")
        args = request.get("args") or {}
        reply = {"op": "service_response", "service": service, "result": True}
        if "id" in request:
            reply["id"] = request["id"]
        topics = self.catalog.topics
        if service == "/rosapi/topics":
            reply["values"] = {"topics": list(topics), "types": list(topics.values())}
        elif service == "/rosapi/topics_and_raw_types":
            reply["values"] = {"topics": list(topics), "types": list(topics.values()),
                               "typedefs_full_text": [self.definitions(t) for t in topics.values()]}
        elif service == "/rosapi/topic_type":
            topic = args.get("topic") if isinstance(args, dict) else None
            reply["values"] = {"type": topics.get(topic, "") if isinstance(topic, str) else ""}
        elif service == "/rosapi/get_time":
            sec, nanosec = divmod(round(self.time() * 1e9), 1_000_000_000)
            reply["values"] = {"time": {"sec": sec, "nanosec": nanosec}}
        elif service == "/rosapi/get_ros_version":
            reply["values"] = dict(ROS_VERSION)
        elif service == "/rosapi/services":
            reply["values"] = {"services": list(SERVICES)}
        elif service == "/rosapi/nodes":
            reply["values"] = {"nodes": [NODE]}
        else:
            raise BadRequest(f"call_service: no service {service} (there are "
                             f"{', '.join(SERVICES)})")
        return [reply]

    def _set_level(self, client: ClientState, request: dict) -> list[dict]:
        return []  # status verbosity: errors are all we send

    # op -> handler: the class's own methods
    OPS: dict[str, Callable[["Protocol", ClientState, dict], list[dict]]] = {
        "subscribe": _subscribe, "unsubscribe": _unsubscribe, "advertise": _advertise,
        "unadvertise": _unadvertise, "publish": _publish, "call_service": _call_service,
        "set_level": _set_level,
    }


def _string(request: dict, key: str) -> str:
    value = request.get(key)
    if not isinstance(value, str) or not value:
        raise BadRequest(f"{request.get('op')}: '{key}' must be a non-empty string")
    return value


def status(level: str, message: str, request_id: Any = None) -> dict:
    """A rosbridge ``status`` message (how rosbridge tells a client its request failed)."""
    reply = {"op": "status", "level": level, "msg": message}
    if request_id is not None:
        reply["id"] = request_id
    return reply
