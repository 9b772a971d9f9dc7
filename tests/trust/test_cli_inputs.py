"""The command line answers every input precisely: options, output paths, user code, signals."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
import yaml

from pymunk_bot.cli import main
from pymunk_bot.config.checks import check_seed
from bounds import HANG_GUARD

REPO = Path(__file__).resolve().parents[2]
PLAIN = {"name": "plain", "world": {"size": [4.0, 4.0], "duration": 1.0},
         "robots": [{"name": "r", "pose": [1.0, 1.0, 0.0]}]}


def cli(*args: str, cwd: Path = REPO, **kwargs) -> subprocess.CompletedProcess:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "pymunk_bot", *args], capture_output=True,
                          text=True, cwd=cwd, env=env, timeout=HANG_GUARD, **kwargs)


def one_line_exit_2(capsys, argv: list[str], *fragments: str) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("error: ") and "Traceback" not in err
    for fragment in fragments:
        assert fragment in err, err


def test_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.startswith("pymunk-bot ")


@pytest.mark.parametrize("argv, fragment", [
    (["--seed", "-1"], "--seed"), (["--seed", "1.7"], "--seed"),
    (["--duration", "inf"], "--duration"), (["--duration", "nan"], "--duration"),
    (["--duration", "0"], "--duration"), (["--duration", "-3"], "--duration"),
])
def test_bad_seed_and_duration_are_one_line(capsys, argv, fragment):
    one_line_exit_2(capsys, ["run", "--headless", *argv], fragment)


@pytest.mark.parametrize("option, target, problem", [
    ("--out", "/no/such/dir/r.json", "does not exist"),
    ("--out", "{tmp}", "is a directory"),
    ("--out", "/proc/r.json", "cannot write"),
    ("--log", "/proc/run.npz", "cannot write"),
    ("--record", "/proc/run.mp4", "cannot write"),
    ("--log", "/no/such/dir/run.npz", "does not exist"),
])
def test_every_output_path_is_checked_before_the_run(tmp_path, capsys, monkeypatch, option,
                                                    target, problem):
    from pymunk_bot import Simulation

    ran = []
    monkeypatch.setattr(Simulation, "run", lambda self, d: ran.append(d))
    code = main(["run", "--headless", option, target.format(tmp=tmp_path)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and not ran
    assert err.startswith(f"error: {option}: ") and problem in err and "\n" not in err


def test_sigterm_during_record_leaves_no_part_file(tmp_path):
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(REPO)}
    video = tmp_path / "maze.mp4"
    # A long recording, so it is surely still writing when the signal comes, however fast
    # or loaded the machine.
    proc = subprocess.Popen([sys.executable, "-m", "pymunk_bot", "run", "maze", "--record",
                             str(video), "--duration", "600"], cwd=REPO, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + HANG_GUARD
    while not list(tmp_path.glob("*.part*")) and time.monotonic() < deadline:
        time.sleep(0.1)  # wait until the recording has started writing
    assert list(tmp_path.glob("*.part*")), "the recording never started"
    proc.send_signal(signal.SIGTERM)
    proc.wait(timeout=HANG_GUARD)
    assert proc.returncode != 0
    assert list(tmp_path.iterdir()) == []



SIGTERM_IN_A_CALLBACK = """
import signal, sys
from pymunk_bot.cli import main
from pymunk_bot.physics.world import World

begin = World._begin
def begin_then_terminated(self, *args):
    signal.raise_signal(signal.SIGTERM)  # its handler runs inside pymunk's C callback
    begin(self, *args)
World._begin = begin_then_terminated
sys.exit(main(["run", "push_crate", "--headless"]))
"""


def test_sigterm_inside_a_pymunk_callback_still_ends_the_run(tmp_path):
    # A SystemExit raised inside a callback from C is printed and dropped there; the run must
    # still stop at the next tick with SIGTERM's status, not run on to its end.
    script = tmp_path / "terminated.py"
    script.write_text(SIGTERM_IN_A_CALLBACK)
    done = subprocess.run([sys.executable, str(script)], cwd=REPO, capture_output=True,
                          text=True, timeout=HANG_GUARD,
                          env={**os.environ, "PYTHONPATH": str(REPO)})
    assert done.returncode == 128 + signal.SIGTERM, done.stderr[-2000:]
    assert "Traceback" not in done.stderr

USER_MODULE = '''
from pathlib import Path
from pymunk_bot.controllers import Controller, wheel_speeds

Path(__file__).with_name("imported.flag").write_text("user code ran")

class Crashy(Controller):
    def __init__(self, robot, when="compute"):
        super().__init__()
        if when == "init":
            raise RuntimeError("broken constructor")
        self.when = when

    def compute(self, obs):
        raise ZeroDivisionError("bug in compute")
'''


@pytest.fixture
def user_project(tmp_path):
    (tmp_path / "crashy.py").write_text(textwrap.dedent(USER_MODULE))
    data = dict(PLAIN, robots=[dict(PLAIN["robots"][0], controller={
        "type": "python", "class_path": "crashy:Crashy"})])
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    data["robots"][0]["controller"]["params"] = {"when": "init"}
    (tmp_path / "init.yaml").write_text(yaml.safe_dump(data))
    return tmp_path


def test_validate_runs_no_user_code_and_leaves_sys_path_alone(user_project, capsys):
    before = list(sys.path)
    assert main(["validate", str(user_project / "s.yaml")]) == 0
    assert not (user_project / "imported.flag").exists()
    assert sys.path == before


def test_a_bug_in_a_users_controller_is_exit_1_with_its_traceback(user_project, capsys):
    before = list(sys.path)
    for name, where in (("s.yaml", "bug in compute"), ("init.yaml", "broken constructor")):
        assert main(["run", str(user_project / name), "--headless"]) == 1
        err = capsys.readouterr().err
        assert "Traceback" in err and where in err and "crashy.py" in err
        assert "error: controller crashy:Crashy" in err
    assert sys.path == before


def test_class_path_resolves_next_to_the_scenario_from_any_folder(tmp_path):
    proc = cli("run", str(REPO / "examples" / "wall_follower.yaml"), "--headless",
               "--duration", "2", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr


def test_pymunk_bot_test_without_arguments_outside_the_repository(tmp_path, capsys,
                                                                   monkeypatch):
    monkeypatch.chdir(tmp_path)
    from pymunk_bot.cli import test as scenario_tests

    ran = []
    monkeypatch.setattr(scenario_tests, "_run_with_progress",
                        lambda paths, seed, jobs: ran.extend(paths) or [])
    main(["test"])
    out = capsys.readouterr().out
    assert "running the shipped scenarios" in out and len(ran) >= 8


def test_plot_ranges_of_a_log_without_lidar_is_one_line(tmp_path, capsys):
    log = tmp_path / "run.npz"
    scenario = tmp_path / "s.yaml"
    scenario.write_text(yaml.safe_dump(PLAIN))
    assert main(["run", str(scenario), "--headless", "--log", str(log)]) == 0
    capsys.readouterr()
    assert main(["plot", str(log), "--kind", "ranges"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --kind: ranges: the log has no LiDAR") and "\n" not in err
    assert not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize("seed, error", [(-1, ValueError), (1.7, TypeError), (True, TypeError),
                                         (2**64, ValueError), ("3", TypeError)])
def test_check_seed_refuses_what_numpy_would_misread(seed, error):
    with pytest.raises(error, match="seed"):
        check_seed(seed)


def test_check_seed_accepts_integers():
    import numpy as np

    assert check_seed(None) is None and check_seed(0) == 0 and check_seed(np.int64(7)) == 7
