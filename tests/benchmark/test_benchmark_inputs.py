"""`pymunk-bot benchmark` under bad input: one line on stderr and exit 2, in bounded time; and
its progress when stderr is not a terminal (CI logs, notebooks)."""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import types
from pathlib import Path

import pytest
import yaml

from pymunk_bot.cli import main
from pymunk_bot.sweep import BackendUnavailable
from pymunk_bot.sweep import backends

REPO = Path(__file__).resolve().parents[2]
PLAIN = {"name": "plain", "world": {"size": [4.0, 4.0], "duration": 0.5},
         "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0],
                     "goal": {"position": [3.0, 3.0]}}]}
HANG_GUARD = 60  # [s] of wall time: only against a hang; the checks below bound CPU time


@pytest.fixture
def scenario(tmp_path):
    path = tmp_path / "plain.yaml"
    path.write_text(yaml.safe_dump(PLAIN))
    return path


def cli(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "pymunk_bot", *args],
                          capture_output=True, text=True, cwd=REPO, env=env, timeout=HANG_GUARD)


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def assert_one_line_exit_2(proc: subprocess.CompletedProcess, *fragments: str) -> None:
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in lines[0], \
        proc.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_a_suite_of_bytes_that_are_not_utf8(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_bytes(b"\xff\xfe\x00name: x\n")
    assert_one_line_exit_2(cli("benchmark", str(bad), "--controller", "navigate", "--backend", "serial",
                               "--out", str(tmp_path / "e.csv")), str(bad), "not UTF-8")


@pytest.mark.parametrize("kind", ["dev_zero", "fifo"])
def test_a_suite_that_is_no_regular_file_answers_at_once(tmp_path, kind):
    if kind == "fifo":
        suite = tmp_path / "pipe.yaml"
        os.mkfifo(suite)
    else:
        suite = Path("/dev/zero")
    assert_one_line_exit_2(cli("benchmark", str(suite), "--controller", "navigate", "--backend", "serial",
                               "--out", str(tmp_path / "e.csv")), str(suite),
                           "not a regular file")


@pytest.mark.parametrize("workers", ["0", "-1", "5000"])
def test_workers_out_of_range_is_refused_as_sweep_refuses_it(scenario, tmp_path, capsys,
                                                             workers):
    for command in (["benchmark", str(scenario), "--controller", "navigate"],
                    ["sweep", str(scenario)]):
        status = main([*command, "--workers", workers, "--out", str(tmp_path / "e.csv"),
                       "--no-progress"])
        err = capsys.readouterr().err.strip().splitlines()
        assert status == 2 and len(err) == 1, err
        assert "--workers" in err[0] and "[1, 1024]" in err[0] and f"got {workers}" in err[0]
    assert not (tmp_path / "e.csv").exists()


@pytest.mark.parametrize("command", ["benchmark", "sweep"])
def test_seeds_beyond_the_cap_are_refused_naming_it(scenario, tmp_path, capsys, command):
    extra = ["--controller", "navigate"] if command == "benchmark" else []
    status = main([command, str(scenario), *extra, "--seeds", "0:10000000000000",
                   "--out", str(tmp_path / "e.csv"), "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1, err
    assert "--seeds" in err[0] and "10000000000000 seeds" in err[0] and "1000000" in err[0]
    assert "1000001" not in err[0]


def test_episodes_beyond_the_cap_name_the_product(scenario, tmp_path, capsys):
    status = main(["benchmark", str(scenario), "--controller", "navigate", "--controller",
                   "avoid", "--seeds", "0:600000", "--out", str(tmp_path / "e.csv"),
                   "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1, err
    assert "1 scenarios x 2 controllers x 600000 seeds = 1200000 episodes" in err[0]
    assert "at most 1000000" in err[0]


def test_a_dead_dask_scheduler_is_refused_at_once(scenario, tmp_path):
    pytest.importorskip("distributed")
    before = children_cpu()
    for command in (["benchmark", str(scenario), "--controller", "navigate"],
                    ["sweep", str(scenario)]):
        proc = cli(*command, "--backend", "dask", "--address", "127.0.0.1:1",
                   "--out", str(tmp_path / "e.csv"))
        assert_one_line_exit_2(proc, "127.0.0.1:1", "Dask scheduler")
    assert children_cpu() - before < 30  # [s] of CPU for two start-ups: no retry loop


def test_the_ray_connect_is_bounded_before_ray_is_asked(monkeypatch):
    """ray.init(address=...) of a dead head retries for minutes: the address is reached first
    (the same bounded probe as Dask's), and ray.init is never called."""
    calls = []
    fake = types.ModuleType("ray")
    fake.is_initialized = lambda: False  # type: ignore[attr-defined]
    fake.init = lambda *a, **k: calls.append((a, k))  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "ray", fake)
    from pymunk_bot.benchmark import controller_choices, load_suite, run_benchmark

    entries = load_suite(str(REPO / "scenarios" / "corridor.yaml"))
    with pytest.raises(BackendUnavailable, match=r"Ray head at 127\.0\.0\.1:1: .*refused"):
        run_benchmark(entries, controller_choices(["navigate"]), [0], backend="ray",
                      address="127.0.0.1:1")
    assert calls == []


@pytest.mark.parametrize("address, problem", [
    ("127.0.0.1:1", "refused"), ("tcp://127.0.0.1:1", "refused"),
    ("127.0.0.1:99999", "port"), ("tcp://:1", "no host"),
])
def test_reach_scheduler_answers_in_bounded_time(address, problem):
    with pytest.raises(BackendUnavailable) as error:
        backends.reach_scheduler(address, "the Dask scheduler", default_port=8786)
    assert address in str(error.value) and problem in str(error.value)


def test_progress_without_a_terminal_is_a_few_lines_with_time_left(scenario, tmp_path, capsys):
    status = main(["benchmark", str(scenario), "--controller", "go_to_goal", "--seeds", "0:40",
                   "--backend", "serial", "--out", str(tmp_path / "e.csv")])
    assert status == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if line]
    assert 2 <= len(lines) <= 21, lines  # bounded: at most one line per 5 %, and the end
    assert all(line.startswith("benchmark: ") and "/40 episodes" in line for line in lines)
    assert "left" in lines[0] and lines[-1].startswith("benchmark: 40/40 episodes")


def test_no_progress_means_no_lines(scenario, tmp_path, capsys):
    assert main(["benchmark", str(scenario), "--controller", "go_to_goal", "--seeds", "0:3",
                 "--backend", "serial", "--out", str(tmp_path / "e.csv"),
                 "--no-progress"]) == 0
    assert capsys.readouterr().err == ""
