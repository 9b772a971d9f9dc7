"""Nothing is lost when the disk fills at the end of a run or the run is interrupted: the
result is written first, the output that did not fit is one line naming its file (exit 2),
what was complete stays, and no empty folder or hidden temporary file is left behind.

The full disk is simulated in-process: every file opened for writing under a folder goes
through a writer that raises ENOSPC (as a full file system does) once the disk is "full",
on write and on the flush at close, as Python's buffered files do."""
from __future__ import annotations

import builtins
import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pymunk_bot.cli import main
from pymunk_bot.localization.tum import read_tum

PLAIN = """\
name: plain
world: {size: [4.0, 3.0], duration: 30.0}
robots:
  - {name: r1, pose: [1.0, 1.5, 0.0], lidar: {beams: 36}, controller: {type: go_to_goal},
     goal: {position: [3.5, 1.5]}}
"""


@pytest.fixture(scope="module")
def scenario(tmp_path_factory) -> str:
    """A scenario without expectations (a run of any length passes), outside ``tmp_path``."""
    path = tmp_path_factory.mktemp("scenario") / "plain.yaml"
    path.write_text(PLAIN)
    return str(path)


class FullDisk:
    """Files opened for writing under ``root``: the disk is full once ``full_when(name)`` was
    true for a file written to (that write fails too), or once ``budget`` bytes were written."""

    def __init__(self, root: Path, full_when=lambda name: False, budget: int = 1 << 40) -> None:
        self.root, self.full_when, self.budget = str(root), full_when, budget
        self.full = False
        self.written = 0
        self.refused: list[str] = []  # names of the files a write to failed

    def open(self, real_open):
        disk = self

        def fake_open(file, mode="r", *args, **kwargs):
            handle = real_open(file, mode, *args, **kwargs)
            if not isinstance(file, (str, os.PathLike)) or not any(c in mode for c in "wax+"):
                return handle
            if not os.path.abspath(os.fspath(file)).startswith(disk.root):
                return handle
            return _Filling(handle, os.path.basename(os.fspath(file)), disk)

        return fake_open

    def take(self, name: str, size: int) -> None:
        if not self.full and (self.full_when(name) or self.written + size > self.budget):
            self.full = True
        if self.full:
            self.refused.append(name)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self.written += size


class _Filling:
    def __init__(self, handle, name: str, disk: FullDisk) -> None:
        self._handle, self._name, self._disk = handle, name, disk
        self._failed = False

    def write(self, data) -> int:
        try:
            self._disk.take(self._name, len(data))
        except OSError:
            self._failed = True
            raise
        return self._handle.write(data)

    def flush(self) -> None:
        self._handle.flush()

    def close(self) -> None:
        self._handle.close()
        if self._failed:  # the buffered tail could not be flushed either
            self._failed = False
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __getattr__(self, name):
        return getattr(self._handle, name)


@pytest.fixture
def full_disk(monkeypatch, tmp_path):
    def make(**kwargs) -> FullDisk:
        disk = FullDisk(tmp_path, **kwargs)
        monkeypatch.setattr(builtins, "open", disk.open(builtins.open))
        return disk

    return make


def hidden(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob(".*"))


def test_a_full_disk_while_writing_trajectories_keeps_the_result_and_the_complete_files(
        scenario, tmp_path, capsys, full_disk):
    disk = full_disk(full_when=lambda name: "odometry" in name)
    out, trajectories = tmp_path / "result.json", tmp_path / "traj"
    code = main(["run", scenario, "--headless", "--duration", "2", "--out", str(out),
                 "--trajectory-out", str(trajectories)])
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert disk.refused, "the simulated disk was never written to"
    assert code == 2
    assert len(err) == 1 and "Traceback" not in captured.err, captured.err
    assert "r1.odometry.tum" in err[0] and "No space left on device" in err[0]
    result = json.loads(out.read_text())  # the run's result was written first
    assert result["sim_time"] == pytest.approx(2.0) and result["robots"]["r1"]["distance"] > 0
    assert "simulated" in captured.out  # and the summary told
    times, poses = read_tum(trajectories / "r1.truth.tum")  # what was complete stays
    assert times[-1] == pytest.approx(2.0, abs=0.05) and len(poses) == len(times)
    assert sorted(p.name for p in trajectories.iterdir()) == ["r1.truth.tum"]
    assert hidden(tmp_path) == []


def test_a_full_disk_at_the_end_of_a_bag_keeps_the_result(scenario, tmp_path, capsys, full_disk):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    disk = full_disk(budget=2000)  # the bag's header fits, its messages do not
    out, bag = tmp_path / "result.json", tmp_path / "x.mcap"
    code = main(["run", scenario, "--headless", "--duration", "2", "--out", str(out),
                 "--log", str(bag), "--profile", "ros2"])
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert disk.refused, "the simulated disk was never full"
    assert code == 2
    assert len(err) == 1 and "Traceback" not in captured.err, captured.err
    assert str(bag) in err[0] and "No space left on device" in err[0]
    assert json.loads(out.read_text())["sim_time"] == pytest.approx(2.0)
    assert not bag.exists() and hidden(tmp_path) == []  # an incomplete bag is no bag


def test_a_full_disk_for_the_result_itself_is_one_line(scenario, tmp_path, capsys, full_disk):
    full_disk(full_when=lambda name: "result" in name)
    out = tmp_path / "result.json"
    code = main(["run", scenario, "--headless", "--duration", "1", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and str(out) in err[0] and "No space" in err[0]
    assert not out.exists() and hidden(tmp_path) == []


def _interrupt_after_a_while(monkeypatch, exception: BaseException) -> None:
    from pymunk_bot.cli.outputs import RunOutputs

    def interrupted_run(self, sim, duration):
        sim.run(0.5)
        raise exception

    monkeypatch.setattr(RunOutputs, "run_headless", interrupted_run)


def test_ctrl_c_with_trajectory_out_leaves_no_empty_folder(scenario, tmp_path, capsys,
                                                           monkeypatch):
    _interrupt_after_a_while(monkeypatch, KeyboardInterrupt())
    trajectories = tmp_path / "traj"
    code = main(["run", scenario, "--headless", "--duration", "5",
                 "--trajectory-out", str(trajectories)])
    assert code == 130 and capsys.readouterr().err.strip() == "interrupted"
    assert list(tmp_path.iterdir()) == []


def test_sigterm_with_trajectory_out_leaves_no_empty_folder(scenario, tmp_path, monkeypatch):
    _interrupt_after_a_while(monkeypatch, SystemExit(128 + signal.SIGTERM))
    trajectories = tmp_path / "traj"
    with pytest.raises(SystemExit):
        main(["run", scenario, "--headless", "--duration", "5",
              "--trajectory-out", str(trajectories)])
    assert list(tmp_path.iterdir()) == []


def test_trajectory_out_into_a_folder_that_exists_keeps_its_other_files(scenario, tmp_path):
    trajectories = tmp_path / "traj"
    trajectories.mkdir()
    (trajectories / "notes.txt").write_text("mine")
    assert main(["run", scenario, "--headless", "--duration", "1",
                 "--trajectory-out", str(trajectories)]) == 0
    assert sorted(p.name for p in trajectories.iterdir()) == [
        "notes.txt", "r1.estimate.tum", "r1.odometry.tum", "r1.truth.tum"]
    assert hidden(tmp_path) == []


def test_the_temporary_file_of_a_killed_run_is_removed_by_the_next_run(scenario, tmp_path):
    """SIGKILL cannot be caught: the next run writing the same log removes what it left."""
    pytest.importorskip("rosbags")
    bag = tmp_path / "x.mcap"
    argv = [sys.executable, "-m", "pymunk_bot", "run", scenario, "--headless",
            "--duration", "3600", "--log", str(bag), "--profile", "ros2"]
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    child = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(1200):  # up to 2 min on a busy machine, for the import and the start
            if hidden(tmp_path) or child.poll() is not None:
                break
            time.sleep(0.1)
    finally:
        child.kill()
        child.wait()
    left = hidden(tmp_path)
    assert len(left) == 1 and left[0].endswith(".mcap.tmp"), left  # what SIGKILL leaves
    argv[argv.index("3600")] = "1"
    assert subprocess.run(argv, env=env, capture_output=True, check=False).returncode == 0
    assert bag.exists() and hidden(tmp_path) == []
