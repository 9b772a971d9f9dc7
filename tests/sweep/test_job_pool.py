"""JobPool: rounds of jobs on one open backend, results in job order (the ES recipe's
candidates; tests/examples/test_train_es.py runs it on a loopback Dask cluster)."""
from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from bounds import HANG_GUARD
from pymunk_bot.sweep.backends import BackendUnavailable, JobPool


def finish_in_turn(job: tuple[int, str]) -> tuple[int, int]:
    """Job 0 waits until job 2 has run: the jobs finish out of their order. (index, pid)"""
    index, flag = job
    if index == 0:
        deadline = time.monotonic() + HANG_GUARD
        while not Path(flag).exists() and time.monotonic() < deadline:
            time.sleep(0.01)
    if index == 2:
        Path(flag).touch()
    return index, os.getpid()


def test_results_come_in_job_order_though_the_jobs_finish_out_of_it(tmp_path):
    flag = str(tmp_path / "job 2 ran")
    with JobPool("process", workers=2) as pool:
        first = pool.map(finish_in_turn, [(k, flag) for k in range(3)])
        second = pool.map(finish_in_turn, [(k, flag) for k in range(3, 7)])
    assert [index for index, _ in first] == [0, 1, 2]
    assert [index for index, _ in second] == [3, 4, 5, 6]
    pids = {pid for _, pid in first + second}
    assert len(pids) == 2 and os.getpid() not in pids  # both rounds on the same two workers


def test_serial_runs_here():
    with JobPool("serial") as pool:
        assert pool.map(abs, [-1, 2, -3]) == [1, 2, 3]


@pytest.mark.parametrize("kwargs, message", [
    ({"backend": "process", "address": "127.0.0.1:8786"},
     "--address is for the dask and ray backends, not 'process'"),
    ({"backend": "process", "workers": 0}, "--workers must be in [1, 1024] (got 0)"),
    ({"backend": "threads"}, "unknown backend 'threads' (choose from serial, process, dask, ray)"),
])
def test_bad_settings_are_refused_before_anything_starts(kwargs, message):
    with pytest.raises(ValueError) as error:
        JobPool(**kwargs)
    assert str(error.value).startswith(message)


def test_an_unreachable_scheduler_is_one_line():
    pytest.importorskip("distributed")
    with pytest.raises(BackendUnavailable,
                       match=r"^cannot reach the Dask scheduler at 127.0.0.1:9: .*refused"):
        with JobPool("dask", address="127.0.0.1:9"):
            pass


def test_map_outside_the_with_block_is_an_error():
    pool = JobPool("serial")
    with pytest.raises(RuntimeError, match="outside its `with` block"):
        pool.map(abs, [1])
