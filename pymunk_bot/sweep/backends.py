"""Where the chunks run: here (serial), local processes, a Dask cluster or a Ray cluster.

Every backend takes the same chunks and yields each chunk's rows as soon as it finishes (in
any order); the caller writes them down at once, so a worker that dies loses only the chunk
it was running. ``JobPool`` keeps one backend open for rounds of other jobs (the ES recipe's
generations of candidates) and gives their results in job order.
"""
from __future__ import annotations

import logging
import os
import socket
from contextlib import ExitStack, contextmanager
from types import ModuleType
from typing import Any, Callable, Iterator, Sequence

from pymunk_bot.sweep.runner import run_chunk

BACKENDS = ("serial", "process", "dask", "ray")
CONNECT_TIMEOUT = 10.0  # [s] to reach a cluster's scheduler
MAX_WORKERS = 1024  # local worker processes at most
DASK_PORT, RAY_PORT = 8786, 6379  # where a scheduler listens when an address names no port
Rows = list[dict]


class BackendUnavailable(RuntimeError):
    """The backend's library is missing or its cluster cannot be reached (one-line reason)."""


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
               else (os.cpu_count() or 1))


def check_workers(workers: int | None) -> None:
    """ValueError naming ``--workers`` unless it is None (one per CPU) or in [1, MAX_WORKERS];
    0 is refused, not read as "every core", so no value of it is silently replaced."""
    if workers is not None and not 1 <= workers <= MAX_WORKERS:
        raise ValueError(f"--workers must be in [1, {MAX_WORKERS}] (got {workers}); leave it "
                         "out for one per CPU")


def reach_scheduler(address: str, what: str, default_port: int) -> None:
    """Open (and close) a TCP connection to ``address`` within CONNECT_TIMEOUT, so that a
    dead or mistyped cluster address is one BackendUnavailable line at once, whatever the
    cluster library would do (Ray retries a dead head for minutes). ``what`` names the
    server in the message ("the Dask scheduler"); ``tcp://``, ``tls://`` and ``ray://`` are
    reached over TCP, other transports are left to their library."""
    scheme, _, rest = address.rpartition("://")
    if scheme not in ("", "tcp", "tls", "ray"):
        return  # another transport (ucx, inproc): its library bounds its own connect
    host, colon, port_text = rest.rstrip("/").rpartition(":")
    if not colon:
        host, port_text = rest.rstrip("/"), str(default_port)
    host = host.strip("[]")  # an IPv6 literal: [::1]:8786
    if not host:
        raise BackendUnavailable(f"cannot reach {what} at {address}: no host in the address")
    if not port_text.isdigit() or not 0 < int(port_text) < 65536:
        raise BackendUnavailable(f"cannot reach {what} at {address}: the port must be a "
                                 f"number in [1, 65535]")
    try:
        with socket.create_connection((host, int(port_text)), timeout=CONNECT_TIMEOUT):
            pass
    except OSError as exc:  # refused, unreachable, unknown host, or no answer in time
        reason = f"no answer within {CONNECT_TIMEOUT:g} s" if isinstance(exc, TimeoutError) \
            else exc.strerror or str(exc)
        raise BackendUnavailable(f"cannot reach {what} at {address}: {reason}") from None


def run_chunks(backend: str, base: dict, source: str, chunks: Sequence[Sequence[Any]],
               duration: float | None, workers: int | None, address: str | None,
               base_dir: str | None = None, task: Callable[..., Rows] | None = None
               ) -> Iterator[Rows]:
    """Rows of each chunk, in completion order (``base_dir``: where the scenario's Python
    controllers are looked for, as :func:`~pymunk_bot.config.parse_scenario` takes it).
    ``task(base, source, chunk, duration, base_dir)`` runs one chunk (a top-level function,
    so every backend can ship it: the sweep's :func:`run_chunk` by default, or another front
    end's, e.g. the benchmark's)."""
    runners: dict[str, Callable[..., Iterator[Rows]]] = {
        "serial": _serial, "process": _process, "dask": _dask, "ray": _ray}
    if backend not in runners:
        raise ValueError(f"unknown backend '{backend}' (choose from {', '.join(BACKENDS)})")
    if address is not None and backend not in ("dask", "ray"):
        raise ValueError(f"--address is for the dask and ray backends, not '{backend}'")
    yield from runners[backend](base, source, chunks, duration, workers, address, base_dir,
                                task or run_chunk)


def _serial(base, source, chunks, duration, workers, address, base_dir, task) -> Iterator[Rows]:
    for chunk in chunks:
        yield task(base, source, chunk, duration, base_dir)


def _process(base, source, chunks, duration, workers, address, base_dir, task) -> Iterator[Rows]:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    # spawn: the same behaviour on every OS, and no fork of a process holding threads.
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers or default_workers(),
                             mp_context=context) as pool:
        futures = [pool.submit(task, base, source, chunk, duration, base_dir)
                   for chunk in chunks]
        try:
            for future in as_completed(futures):
                yield future.result()
        finally:
            for future in futures:
                future.cancel()


@contextmanager
def dask_client(workers: int | None, address: str | None) -> Iterator[Any]:
    """A ``distributed.Client`` on the Dask scheduler at ``address``, or on a new cluster of
    ``workers`` processes on 127.0.0.1 (one per CPU if None) when there is no address; closed
    (and the local cluster stopped) on leaving. BackendUnavailable, one line, when Dask is
    missing or the scheduler cannot be reached."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise BackendUnavailable("the dask backend needs dask.distributed: "
                                 "pip install 'pymunk-bot[dask]'") from None
    cluster = None
    try:
        if address is None:
            # Loopback only: a sweep on one machine opens no port to the network.
            cluster = LocalCluster(n_workers=workers or default_workers(), threads_per_worker=1,
                                   processes=True, host="127.0.0.1", dashboard_address=None,
                                   silence_logs=logging.CRITICAL)  # no shutdown chatter
            client = Client(cluster)
        else:
            reach_scheduler(address, "the Dask scheduler", DASK_PORT)
            client = Client(address, timeout=f"{CONNECT_TIMEOUT}s")
    except (OSError, TimeoutError) as exc:
        if cluster is not None:
            cluster.close()
        raise BackendUnavailable(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _dask(base, source, chunks, duration, workers, address, base_dir, task) -> Iterator[Rows]:
    from distributed import as_completed

    with dask_client(workers, address) as client:
        base_future = client.scatter(base, broadcast=True)
        futures = [client.submit(task, base_future, source, chunk, duration, base_dir,
                                 pure=False)
                   for chunk in chunks]
        try:
            for future in as_completed(futures):
                yield future.result()
        finally:
            client.cancel(futures)


@contextmanager
def ray_session(workers: int | None, address: str | None) -> Iterator[Any]:
    """The ``ray`` module, connected to the Ray cluster at ``address`` (``auto``: the one on
    this machine) or to a new local instance of ``workers`` CPUs; shut down on leaving if it
    was started here. BackendUnavailable, one line, when Ray is missing or the head cannot be
    reached."""
    try:
        import ray
    except ImportError:
        raise BackendUnavailable("the ray backend needs ray: pip install 'pymunk-bot[ray]'") from None
    started = False
    if not ray.is_initialized():
        if address is None:
            # A local instance without the dashboard; its node address is loopback, but Ray
            # 2.60's own servers still listen on every interface (see docs/sweeps.md).
            ray.init(num_cpus=workers or default_workers(), include_dashboard=False,
                     _node_ip_address="127.0.0.1", log_to_driver=False)
        else:
            if address != "auto":  # "auto": a cluster on this machine, found by its files
                reach_scheduler(address, "the Ray head", RAY_PORT)
            ray.init(address=address, log_to_driver=False)
        started = True
    try:
        yield ray
    finally:
        if started:
            ray.shutdown()


def _ray(base, source, chunks, duration, workers, address, base_dir, task) -> Iterator[Rows]:
    with ray_session(workers, address) as ray:
        remote = ray.remote(num_cpus=1)(task)
        base_ref = ray.put(base)
        pending = [remote.remote(base_ref, source, chunk, duration, base_dir) for chunk in chunks]
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                yield ray.get(done[0])
        finally:
            for ref in pending:
                ray.cancel(ref)


class JobPool:
    """Runs rounds of jobs on one backend, opened once for all of them (a trainer evaluates
    a generation of candidates after another on the same workers, which keep what they
    cached): ``with JobPool("dask", address=...) as pool: results = pool.map(task, jobs)``.

    ``map`` returns ``task(job)`` for every job **in the order of the jobs**, whatever order
    they finish in, so a caller that draws every random number itself gets the same results
    on every backend and worker count. ``task`` is a top-level function of one picklable
    argument; it must be importable where the jobs run, or live in one of ``by_value``'s
    modules (e.g. a script's own module, which a remote worker does not have), whose code is
    then shipped with the jobs. Opening the pool raises ValueError (``--workers``,
    ``--address``, an unknown backend) or BackendUnavailable, one line each, as ``run_chunks``
    does.
    """

    def __init__(self, backend: str, workers: int | None = None, address: str | None = None,
                 by_value: Sequence[ModuleType] = ()) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"unknown backend '{backend}' (choose from {', '.join(BACKENDS)})")
        if address is not None and backend not in ("dask", "ray"):
            raise ValueError(f"--address is for the dask and ray backends, not '{backend}'")
        check_workers(workers)
        self.backend, self.workers, self.address = backend, workers, address
        self.by_value = tuple(by_value)
        self._stack = ExitStack()
        self._map: Callable[[Callable[[Any], Any], Sequence[Any]], list] | None = None

    def __enter__(self) -> JobPool:
        try:
            self._map = getattr(self, f"_open_{self.backend}")()
        except BaseException:
            self._stack.close()
            raise
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._map = None
        self._stack.close()

    def map(self, task: Callable[[Any], Any], jobs: Sequence[Any]) -> list:
        """``[task(job) for job in jobs]``, run on the pool's workers."""
        if self._map is None:
            raise RuntimeError("JobPool.map outside its `with` block")
        return self._map(task, jobs)

    def _open_serial(self) -> Callable[[Callable[[Any], Any], Sequence[Any]], list]:
        return lambda task, jobs: [task(job) for job in jobs]

    def _open_process(self) -> Callable[[Callable[[Any], Any], Sequence[Any]], list]:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        # spawn, as run_chunks: the same on every OS, no fork of a process holding threads
        pool = self._stack.enter_context(ProcessPoolExecutor(
            max_workers=self.workers or default_workers(),
            mp_context=multiprocessing.get_context("spawn")))
        return lambda task, jobs: list(pool.map(task, jobs))

    def _open_dask(self) -> Callable[[Callable[[Any], Any], Sequence[Any]], list]:
        client = self._stack.enter_context(dask_client(self.workers, self.address))
        import cloudpickle  # Dask ships functions with it

        self._ship_by_value(cloudpickle)

        def run(task: Callable[[Any], Any], jobs: Sequence[Any]) -> list:
            if self._is_by_value(task):  # Dask pickles a task graph by reference: ship the code
                futures = client.map(_call_pickled, [cloudpickle.dumps(task)] * len(jobs),
                                     list(jobs), pure=False)
            else:
                futures = client.map(task, list(jobs), pure=False)
            try:
                return list(client.gather(futures))  # in the order of the futures
            except BaseException:
                client.cancel(futures)
                raise
        return run

    def _open_ray(self) -> Callable[[Callable[[Any], Any], Sequence[Any]], list]:
        ray = self._stack.enter_context(ray_session(self.workers, self.address))
        self._ship_by_value(ray.cloudpickle)  # Ray ships functions with its own copy

        def run(task: Callable[[Any], Any], jobs: Sequence[Any]) -> list:
            remote = ray.remote(num_cpus=1)(task)
            refs = [remote.remote(job) for job in jobs]
            try:
                return list(ray.get(refs))  # in the order of the refs
            except BaseException:
                for ref in refs:
                    ray.cancel(ref)
                raise
        return run

    def _is_by_value(self, task: Callable[[Any], Any]) -> bool:
        return any(task.__module__ == module.__name__ for module in self.by_value)

    def _ship_by_value(self, pickler: Any) -> None:
        for module in self.by_value:
            if module.__name__ != "__main__":  # a script's functions already travel by value
                pickler.register_pickle_by_value(module)
                self._stack.callback(pickler.unregister_pickle_by_value, module)


def _call_pickled(task: bytes, job: Any) -> Any:
    """``task(job)`` for a task cloudpickled with its code (JobPool's ``by_value``)."""
    import cloudpickle

    return cloudpickle.loads(task)(job)
