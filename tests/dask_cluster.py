"""A real Dask scheduler and worker processes on 127.0.0.1 for tests, stopped afterwards."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest

from bounds import HANG_GUARD


@contextmanager
def loopback_dask_cluster(folder: Path, workers: int = 2, cwd: Path | None = None,
                          pythonpath: Path | None = None) -> Iterator[str]:
    """The scheduler's address (``tcp://127.0.0.1:PORT``) with ``workers`` one-thread worker
    processes connected, run in ``cwd`` with ``pythonpath``; skips the test where the dask
    command line is missing. Workers are stopped first, while the scheduler still answers."""
    pytest.importorskip("distributed")
    dask = Path(sys.executable).with_name("dask")
    if not dask.exists():
        pytest.skip("the dask command line is not installed")
    info = folder / "scheduler.json"
    env = {**os.environ}
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env,
             "cwd": cwd or folder}
    scheduler = subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--no-dashboard", "--scheduler-file", str(info)], **quiet)
    procs = [scheduler]
    try:
        deadline = time.monotonic() + HANG_GUARD
        while not info.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for _ in range(workers):  # no nanny: each worker is one process, quick to stop
            procs.append(subprocess.Popen([str(dask), "worker", address, "--host", "127.0.0.1",
                                           "--nthreads", "1", "--no-nanny", "--no-dashboard"],
                                          **quiet))
        from distributed import Client

        with Client(address, timeout=f"{HANG_GUARD:.0f}s") as client:
            client.wait_for_workers(workers, timeout=HANG_GUARD)
        yield address
    finally:
        for proc in reversed(procs):
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
