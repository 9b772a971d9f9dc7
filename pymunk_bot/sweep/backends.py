"""Where the chunks run: here (serial), local processes, a Dask cluster or a Ray cluster.

Every backend takes the same chunks and yields each chunk's rows as soon as it finishes (in
any order); the caller writes them down at once, so a worker that dies loses only the chunk
it was running.
"""
from __future__ import annotations

import logging
import os
from typing import Any, Callable, Iterator, Sequence

from pymunk_bot.sweep.runner import run_chunk

BACKENDS = ("serial", "process", "dask", "ray")
CONNECT_TIMEOUT = 10.0  # [s] to reach a cluster's scheduler
Rows = list[dict]


class BackendUnavailable(RuntimeError):
    """The backend's library is missing or its cluster cannot be reached (one-line reason)."""


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
               else (os.cpu_count() or 1))


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


def _dask(base, source, chunks, duration, workers, address, base_dir, task) -> Iterator[Rows]:
    try:
        from distributed import Client, LocalCluster, as_completed
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
            client = Client(address, timeout=f"{CONNECT_TIMEOUT}s")
    except (OSError, TimeoutError) as exc:
        if cluster is not None:
            cluster.close()
        raise BackendUnavailable(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        base_future = client.scatter(base, broadcast=True)
        futures = [client.submit(task, base_future, source, chunk, duration, base_dir,
                                 pure=False)
                   for chunk in chunks]
        try:
            for future in as_completed(futures):
                yield future.result()
        finally:
            client.cancel(futures)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _ray(base, source, chunks, duration, workers, address, base_dir, task) -> Iterator[Rows]:
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
            ray.init(address=address, log_to_driver=False)
        started = True
    try:
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
    finally:
        if started:
            ray.shutdown()
