"""The command line as a user runs it: list, validate, run with --out (in this process:
tests/command.py), determinism across processes (in two)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from bounds import HANG_GUARD
from command import pymunk_bot

REPO = Path(__file__).resolve().parent.parent
SCENARIOS = sorted((REPO / "scenarios").glob("*.yaml"))


def cli(*args: str, cwd: Path = REPO, env_extra: dict | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", **(env_extra or {})}
    return subprocess.run([sys.executable, "-m", "pymunk_bot", *args], capture_output=True,
                          text=True, cwd=cwd, env=env, timeout=HANG_GUARD)


def test_list_shows_every_shipped_scenario_with_its_description():
    proc = pymunk_bot("list")
    assert proc.returncode == 0
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("default ")
    for path in SCENARIOS:
        line = next(l for l in lines if l.split()[0] == path.stem)
        assert len(line.split(maxsplit=1)) == 2  # has a description


def test_validate_all_shipped():
    proc = pymunk_bot("validate", *SCENARIOS)
    assert proc.returncode == 0, proc.stderr


def test_default_scenario_runs_from_any_directory(tmp_path):
    out = tmp_path / "r.json"
    proc = pymunk_bot("run", "--headless", "--out", out, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    result = json.loads(out.read_text())
    assert result["scenario"] == "default" and result["passed"]


def test_run_writes_the_contract_result_shape(tmp_path):
    out = tmp_path / "r.json"
    proc = pymunk_bot("run", "push_crate", "--headless", "--out", out, "--seed", "3", "--duration", "5")
    result = json.loads(out.read_text())
    assert {"scenario", "seed", "sim_time", "steps", "wall_time", "real_time_factor", "passed",
            "robots"} <= result.keys()
    assert result["seed"] == 3 and result["sim_time"] == pytest.approx(5.0)
    assert result["steps"] == 300
    r1 = result["robots"]["r1"]
    assert {"pose", "distance", "collisions", "goal_reached", "time_to_goal"} <= r1.keys()
    assert len(r1["pose"]) == 3
    # 5 s is too short to reach the goal: an expectation fails, so exit status 1
    assert result["passed"] is False and proc.returncode == 1
    assert list(tmp_path.iterdir()) == [out]  # no temporary files left behind


def _strip_timing(result: dict) -> dict:
    return {k: v for k, v in result.items() if k not in ("wall_time", "real_time_factor")}


def test_same_seed_gives_identical_json_in_separate_processes(tmp_path):
    outs = []
    for i, hashseed in enumerate(("1", "987")):
        out = tmp_path / f"r{i}.json"
        cli("run", "push_crate", "--headless", "--out", str(out), "--duration", "8",
            env_extra={"PYTHONHASHSEED": hashseed})  # it pushes the crate from 4.4 s on
        outs.append(_strip_timing(json.loads(out.read_text())))
    assert outs[0] == outs[1]


def test_python_api_of_the_contract():
    import pymunk_bot as pb

    sim = pb.Simulation.from_file(str(REPO / "scenarios" / "push_crate.yaml"), seed=None)
    assert sim.seed == 7
    sim.step()
    sim.run(2.0)
    assert sim.time == pytest.approx(2.0 + 1 / 60)
    r = sim.robots["r1"]
    assert r.pose.shape == (3,)
    r.set_wheel_speeds(0.5, 0.4)
    assert r.odometry.pose.shape == (3,)
    assert r.collisions == 0
    ranges = r.lidar.scan()
    assert ranges.shape == (360,) and r.lidar.angles.shape == (360,)
    ahead = int(abs(r.lidar.angles).argmin())
    crate_face = 4.0 - 0.25
    assert ranges[ahead] == pytest.approx(crate_face - r.pose[0], abs=1e-6)  # the crate
    assert r.lidar.ranges.shape == (360,)
