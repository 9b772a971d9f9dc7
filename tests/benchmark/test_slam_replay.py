"""bench/slam_replay.py: a run recorded and replayed with the same code gives the online run's
keyframes and ATE; settings reach the replayed SLAM; bad input is one line and exit 2."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bench.slam_replay import load, record_run, replay, save

REPO = Path(__file__).resolve().parents[2]
HANG_GUARD = 60  # [s] of wall time: only against a hang


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """The Nav2 depot, typical odometry, seed 0: a short run (about 2 s), saved and loaded."""
    recording = record_run("slam", "depot", "typical", 0)
    if recording is None:
        pytest.skip("the depot map is not in scenarios/maps")
    folder = tmp_path_factory.mktemp("recordings")
    path = save(recording, folder)
    assert path.name == "slam_depot_typical_0.pkl"
    return folder, load(path)


def cli(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "bench.slam_replay", *args], capture_output=True,
                          text=True, cwd=REPO, env=env, timeout=HANG_GUARD)


def test_a_replay_with_unchanged_code_is_the_online_run(recorded):
    _, recording = recorded
    result = replay(recording)
    assert result.keyframes == result.keyframes_online == recording.online_keyframes.shape[0] > 10
    assert result.ate == pytest.approx(recording.online.ate, abs=1e-9)
    assert result.map_precision == pytest.approx(recording.online.map_precision, abs=1e-12)
    assert result.closures == recording.online.closures
    assert result.passed == recording.online.success
    # deterministic: a second replay is the same to the bit
    assert replay(recording).ate == result.ate


def test_settings_reach_the_replayed_slam(recorded):
    _, recording = recorded
    sparse = replay(recording, {"keyframe_d": 0.5})
    assert sparse.keyframes != sparse.keyframes_online
    assert np.isfinite(sparse.ate)
    with pytest.raises(ValueError, match="unknown SLAM key"):
        replay(recording, {"keyframe_distance": 0.5})


def test_the_command_line_replays_and_compares(recorded, tmp_path):
    folder, recording = recorded
    out = tmp_path / "base.json"
    proc = cli("replay", str(folder), "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("ok   slam ") or lines[0].startswith("FAIL slam ")
    assert lines[-1].startswith("slam/depot/typical: ")
    runs = json.loads(out.read_text())["runs"]
    assert runs[0]["ate"] == pytest.approx(recording.online.ate, abs=1e-9)
    proc = cli("compare", str(out), str(out))
    assert proc.returncode == 0 and "differs" not in proc.stdout, proc.stderr


@pytest.mark.parametrize("args, fragment", [
    (["replay", "{missing}"], "no such directory"),
    (["replay", "{empty}"], "no recordings"),
    (["replay", "{stranger}"], "not a slam_replay recording"),
    (["replay", "{empty}", "--settings", '{"keyframe_distance": 0.5}'], "unknown SLAM key"),
    (["record", "--families", "moon", "--out", "{empty}"], "unknown moon"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, fragment):
    (tmp_path / "empty").mkdir()
    (tmp_path / "stranger").mkdir()
    (tmp_path / "stranger" / "x.pkl").write_text("not a pickle")
    paths = {name: str(tmp_path / name) for name in ("missing", "empty", "stranger")}
    proc = cli(*[a.format(**paths) if a.startswith("{") and a[1:-1] in paths else a for a in args])
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and lines[0].startswith("slam_replay: ") and fragment in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr
