"""``run --rosbridge``: a rosbridge v2 server (JSON over WebSocket) fed while the run goes on.

The server runs an asyncio loop (``websockets``) in a thread of its own; the simulation never
waits for it. After each step :class:`BridgeObserver` builds the messages that someone is
subscribed to, encodes each once and hands them to the loop, which queues them per client:
a slow client loses its oldest messages (``CLIENT_QUEUE``), never stalls the run. Requests
are handled by :class:`~.protocol.Protocol`; commands go through a
:class:`~.commands.CommandInbox`. Every bad request, and every command a robot refuses after
the step, is answered with a ``status`` (at most ``STATUS_PER_S`` per client per second, then
one count) and logged as one line (at most ``LOG_LINES_PER_S`` per client, then a count); a
client sending more than ``MAX_REQUESTS_PER_S`` has the excess dropped.
"""
from __future__ import annotations

import asyncio
import collections
import errno
import itertools
import logging
import threading
import time
import weakref
from typing import Any, Callable

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.foxglove.frames import DEFAULT_HOST
from pymunk_bot.foxglove.snapshot import geometry_of_sim
from pymunk_bot.ros2.commands import CommandInbox
from pymunk_bot.ros2.jsonmsg import dumps, loads, to_plain
from pymunk_bot.ros2.messages import LiveMessages, Outgoing, typestore
from pymunk_bot.ros2.names import DEFAULT_PORT, latched, robot_names
from pymunk_bot.ros2.protocol import BadRequest, Catalog, ClientState, Protocol, status, valid_id

CLIENT_QUEUE = 200  # messages waiting for one client; older ones are dropped
MAX_FRAME = 1 << 20  # [bytes] largest request accepted
MAX_REQUESTS_PER_S = 200.0  # per client, sustained
REQUEST_BURST = 400.0  # per client, at once
LOG_LINES_PER_S = 10  # bad-request lines per client per second; the rest are counted
STATUS_PER_S = 10  # status messages per client per second; the rest are counted
START_TIMEOUT = 10.0  # [s]
CLOSE_TIMEOUT = 1.0  # [s] for a client to answer the closing handshake when the server stops


class _Client:
    """One connection: its protocol state, outgoing queue, request budget and log budget."""

    def __init__(self, name: str, connection: Any) -> None:
        self.state = ClientState(name)
        self.connection = connection
        self.outbox: collections.deque[str] = collections.deque(maxlen=CLIENT_QUEUE)
        self.ready = asyncio.Event()
        self.tokens, self.refilled = REQUEST_BURST, time.monotonic()
        self.dropped = 0  # requests dropped for flooding
        self.flood_logged = -1e18  # [s] monotonic: when flooding was last reported
        self.log_window, self.logged, self.suppressed = 0.0, 0, 0
        self.status_window, self.statuses, self.statuses_held = 0.0, 0, 0

    def queue(self, text: str) -> None:
        self.outbox.append(text)
        self.ready.set()

    def status(self, level: str, message: str, request_id: Any = None) -> None:
        """Queue a ``status``: at most STATUS_PER_S a second; the next second's first says how
        many were held back."""
        now = time.monotonic()
        if now - self.status_window >= 1.0:
            if self.statuses_held:
                self.queue(dumps(status("warning", f"{self.statuses_held} more problems with "
                                        f"this client's requests not told (at most "
                                        f"{STATUS_PER_S} a second)")))
            self.status_window, self.statuses, self.statuses_held = now, 0, 0
        if self.statuses < STATUS_PER_S:
            self.statuses += 1
            self.queue(dumps(status(level, message, request_id)))
        else:
            self.statuses_held += 1

    def admit(self) -> bool:
        """Token bucket: may this request be handled?"""
        now = time.monotonic()
        self.tokens = min(REQUEST_BURST, self.tokens + (now - self.refilled) * MAX_REQUESTS_PER_S)
        self.refilled = now
        if self.tokens < 1.0:
            self.dropped += 1
            return False
        self.tokens -= 1.0
        return True


class RosbridgeServer:
    """A rosbridge server on ``host``:``port``; :meth:`stop` it when done."""

    def __init__(self, catalog: Catalog, inbox: CommandInbox, sim_time: Callable[[], float],
                 host: str = DEFAULT_HOST, port: int = DEFAULT_PORT,
                 report: Callable[[str], None] = print) -> None:
        if not 0 <= port <= 65535:
            raise ScenarioError("--port", "", f"must be 0..65535 (got {port})")
        self.host, self.report = host, report
        self.protocol = Protocol(catalog, inbox, sim_time, _definition)
        self._clients: set[_Client] = set()
        self._latched: dict[str, str] = {}
        self._ids = itertools.count(1)
        self.subscribed: frozenset[str] = frozenset()  # topics with a subscriber (any thread reads)
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stopping: asyncio.Event | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._on_stop: list[Callable[[], None]] = []  # run once, by stop()
        self.port = port
        self._thread = threading.Thread(target=self._serve, name="rosbridge", daemon=True)
        self._thread.start()
        if not self._ready.wait(START_TIMEOUT) or self._error is not None:
            error = self._error
            reason = error.strerror if isinstance(error, OSError) else error or "no answer"
            in_use = isinstance(error, OSError) and error.errno == errno.EADDRINUSE
            self.stop()
            raise ScenarioError("--rosbridge", "", f"cannot serve on {host}:{port}: {reason}"
                                f"{' (try another --port)' if in_use else ''}")

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    @property
    def clients(self) -> int:
        return len(self._clients)

    def publish(self, messages: list[Outgoing]) -> None:
        """Send ``messages`` to their subscribers (any thread; encodes here, sends in the loop)."""
        loop = self._loop
        if not messages or loop is None:
            return
        encoded = [(m.topic, dumps({"op": "publish", "topic": m.topic, "msg": to_plain(m.msg)}),
                    latched(m.topic, m.msgtype)) for m in messages]
        try:
            loop.call_soon_threadsafe(self._deliver, encoded)
        except RuntimeError:  # the loop has stopped
            pass

    def stop(self) -> None:
        """Disconnect every client, free the port and end the thread (safe to call twice)."""
        loop, stopping = self._loop, self._stopping
        if loop is not None and stopping is not None:
            try:
                loop.call_soon_threadsafe(stopping.set)
            except RuntimeError:
                pass
        self._thread.join(START_TIMEOUT)
        self._loop = None
        while self._on_stop:
            self._on_stop.pop()()

    def when_stopped(self, action: Callable[[], None]) -> None:
        """Run ``action`` when the server stops (e.g. take its observers off the run)."""
        self._on_stop.append(action)

    # ------------------------------------------------------------------ the loop's thread
    def _serve(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as exc:  # reported by the constructor, or here once serving
            if self._ready.is_set():
                self.report(f"rosbridge: the server stopped: {type(exc).__name__}: {exc}")
            self._error = exc
            self._ready.set()

    async def _main(self) -> None:
        from websockets.asyncio.server import serve

        self._stopping = asyncio.Event()
        server = await serve(self._session, self.host, self.port, max_size=MAX_FRAME,
                             compression=None, close_timeout=CLOSE_TIMEOUT,
                             logger=_one_line_logger(self.report))
        self.port = server.sockets[0].getsockname()[1]
        self._loop = asyncio.get_running_loop()
        self._ready.set()
        async with server:
            await self._stopping.wait()
            server.close()  # closes every connection

    def _deliver(self, encoded: list[tuple[str, str, bool]]) -> None:
        now = time.monotonic()
        for topic, text, keep in encoded:
            if keep:  # latched: the next subscriber gets it at once
                self._latched[topic] = text
            for client in self._clients:
                subscription = client.state.subscriptions.get(topic)
                if subscription is None or now - subscription.last_sent < subscription.throttle:
                    continue
                subscription.last_sent = now
                client.queue(text)

    async def _session(self, connection) -> None:
        from websockets.exceptions import ConnectionClosed

        host, port = connection.remote_address[:2]
        client = _Client(f"client {next(self._ids)} ({host}:{port})", connection)
        client.state.tell = lambda level, message, request_id: self._tell_soon(
            client, level, message, request_id)
        self._clients.add(client)
        sender = asyncio.create_task(self._send(client))
        try:
            async for text in connection:
                self._request(client, text)
        except ConnectionClosed:
            pass  # a client that leaves mid-stream is no error
        finally:
            sender.cancel()
            self._clients.discard(client)
            self._refresh_subscribed()
            if client.suppressed:
                self.report(f"rosbridge: {client.state.name}: {client.suppressed} more bad "
                            "requests not shown")

    async def _send(self, client: _Client) -> None:
        from websockets.exceptions import ConnectionClosed

        try:
            while True:
                await client.ready.wait()
                client.ready.clear()
                while client.outbox:
                    await client.connection.send(client.outbox.popleft())
        except ConnectionClosed:
            pass

    def _tell_soon(self, client: _Client, level: str, message: str, request_id: Any) -> None:
        """From the simulation's thread: a refused command, to the client that sent it."""
        loop = self._loop
        if loop is None:
            return
        try:
            loop.call_soon_threadsafe(self._tell, client, level, message, request_id)
        except RuntimeError:  # the loop has stopped
            pass

    def _tell(self, client: _Client, level: str, message: str, request_id: Any) -> None:
        if client not in self._clients:  # it has left
            return
        self._log(client, message)
        client.status(level, message, request_id)

    def _request(self, client: _Client, text: str | bytes) -> None:
        if not client.admit():
            now = time.monotonic()
            if now - client.flood_logged >= 1.0:  # its own limit: one line a second at most
                client.flood_logged = now
                self.report(f"rosbridge: {client.state.name}: flooding: over "
                            f"{MAX_REQUESTS_PER_S:g} requests/s, {client.dropped} dropped so far")
            return
        before = set(client.state.subscriptions)
        try:
            replies = self.protocol.handle(client.state, text)
        except BadRequest as exc:
            self._log(client, str(exc))
            request_id, service = _id_and_service(text)
            client.status("error", str(exc), request_id)
            if service is not None:  # a service call must get an answer, or the caller waits
                client.queue(dumps({"op": "service_response", "service": service,
                                         "result": False, "values": str(exc),
                                         **({"id": request_id} if request_id is not None else {})}))
            return
        for reply in replies:
            client.queue(dumps(reply))
        if set(client.state.subscriptions) != before:
            for topic in set(client.state.subscriptions) - before:
                if topic in self._latched:
                    client.queue(self._latched[topic])
            self._refresh_subscribed()

    def _refresh_subscribed(self) -> None:
        self.subscribed = frozenset(t for c in self._clients for t in c.state.subscriptions)

    def _log(self, client: _Client, problem: str) -> None:
        """One line per bad request, at most LOG_LINES_PER_S per client per second."""
        now = time.monotonic()
        if now - client.log_window >= 1.0:
            if client.suppressed:
                self.report(f"rosbridge: {client.state.name}: {client.suppressed} more bad "
                            "requests not shown")
            client.log_window, client.logged, client.suppressed = now, 0, 0
        if client.logged < LOG_LINES_PER_S:
            client.logged += 1
            self.report(f"rosbridge: {client.state.name}: {problem}")
        else:
            client.suppressed += 1


def _one_line_logger(report: Callable[[str], None]) -> logging.Logger:
    """A logger for websockets' own messages (a failed handshake, a browser opening the URL):
    warnings and errors as one line each, without traceback; the rest dropped."""
    logger = logging.getLogger("pymunk_bot.rosbridge.websockets")
    logger.propagate = False
    logger.setLevel(logging.WARNING)
    for handler in list(logger.handlers):
        logger.removeHandler(handler)

    class OneLine(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            reason = f": {record.exc_info[1]}" if record.exc_info and record.exc_info[1] else ""
            report(f"rosbridge: {record.getMessage()}{reason}")

    logger.addHandler(OneLine())
    return logger


def _definition(msgtype: str) -> str:
    text, _ = typestore().generate_msgdef(msgtype, ros_version=2)
    return text


def _id_and_service(text: str | bytes) -> tuple[Any, str | None]:
    """The id and service of a request that failed, if it can be read at all."""
    try:
        request = loads(text)
    except ValueError:
        return None, None
    if not isinstance(request, dict):
        return None, None
    service = request.get("service") if request.get("op") == "call_service" else None
    request_id = request.get("id") if valid_id(request.get("id")) else None  # not echoed
    return request_id, service if isinstance(service, str) else None


class BridgeObserver:
    """A simulation observer feeding a :class:`RosbridgeServer` after every step."""

    def __init__(self, server: RosbridgeServer, world_map: Any = None) -> None:
        self.server = server
        self.world_map = world_map
        self._messages: LiveMessages | None = None

    def attach(self, sim) -> "BridgeObserver":
        sim.attach(self)  # on_reset now, then every step
        return self

    def on_reset(self, sim) -> None:
        self._messages = LiveMessages(sim, self.world_map)
        self._every_step = self.server.protocol.catalog.every_step
        # Each sensor with the topic its readings go out on: a reading nobody subscribed to
        # is no reason to sample the run.
        names = robot_names(list(sim.robots))
        self._sensors = [(sensor, names[r.name].topic(kind)) for r in sim.robots.values()
                         for kind, sensor in (("scan", r.sensor("lidar")), ("imu", r.sensor("imu")))
                         if sensor is not None]
        self._readings: list = [None] * len(self._sensors)
        self.server.publish(self._messages.start(sim, self._wanted))

    def _wanted(self, topic: str) -> bool:
        return topic in self.server.subscribed

    def __call__(self, sim) -> None:
        subscribed = self.server.subscribed
        if not subscribed or self._messages is None:
            return  # nobody listens: no snapshot, no messages
        if subscribed.isdisjoint(self._every_step) and not self._new_reading(subscribed):
            return  # only sensor topics wanted, and none of theirs has read since the last step
        self.server.publish(self._messages.step(sim, self._wanted))

    def _new_reading(self, subscribed: Any) -> bool:
        """Whether a LiDAR or IMU on a subscribed topic has read since the last call."""
        new = False
        for k, (sensor, topic) in enumerate(self._sensors):
            reading = sensor.latest if sensor.name == "lidar" else sensor.reading
            if reading is not self._readings[k]:
                self._readings[k] = reading
                new = new or topic in subscribed
        return new


def serve_sim(sim, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT,
              inbox: CommandInbox | None = None, world_map: Any = None,
              report: Callable[[str], None] = print) -> RosbridgeServer:
    """Serve ``sim`` over rosbridge: the server, its observer and the command inbox attached.
    ``world_map``: the OccupancyGrid served on /map (None: no /map)."""
    inbox = (inbox or CommandInbox(report=report)).attach(sim)
    mapping = [r.name for r in sim.robots.values() if r.mapper is not None]
    catalog = Catalog.of_run(geometry_of_sim(sim).meta, world_map is not None, mapping)
    run = weakref.ref(sim)  # the server does not keep the run alive

    def sim_time() -> float:
        alive = run()
        return float(alive.time) if alive is not None else 0.0

    server = RosbridgeServer(catalog, inbox, sim_time, host, port, report)
    # Stopped, the server lets go of the run: no cycle through sim.observers keeps the run
    # alive past the interpreter's own teardown (where freeing a Space crashes cffi).
    server.when_stopped(lambda: sim.detach(inbox))
    try:
        observer = BridgeObserver(server, world_map).attach(sim)
        server.when_stopped(lambda: sim.detach(observer))
    except BaseException:
        server.stop()
        raise
    return server
