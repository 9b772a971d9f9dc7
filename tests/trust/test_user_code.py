"""User code cannot take a run down silently or hang a batch: `sys.exit()` in a controller is
reported like any other failure, and in `test`/`sweep` runs every call into user code has a time
budget (PYMUNK_BOT_CALL_BUDGET) whose overrun fails the run with the controller named."""
from __future__ import annotations

import os
import threading
import time
import uuid

import pytest
import yaml
from bounds import HANG_GUARD

from pymunk_bot.cli import main
from pymunk_bot.controllers.python import CALL_BUDGET_ENV, batch_budget, budgeted, call_budget
from pymunk_bot.config.errors import ControllerError

PLAIN = {"name": "plain", "world": {"size": [4.0, 4.0], "duration": 1.0},
         "robots": [{"name": "r", "pose": [1.0, 1.0, 0.0]}]}

CONTROLLER = '''
import sys, time
from pymunk_bot.controllers import Controller

{on_import}

class User(Controller):
    def __init__(self, robot, where="none"):
        super().__init__()
        self.where = where
        if where == "init":
            time.sleep(1000)  # blocked in C: the alarm still stops it
        if where == "exit-init":
            sys.exit(5)

    def compute(self, obs):
        while self.where == "compute":
            pass
        return (0.1, 0.1)
'''


def project(tmp_path, on_import: str = "", where: str = "none", expect: bool = False):
    """A scenario next to a fresh user module (a unique name: nothing cached between tests)."""
    module = f"user_{uuid.uuid4().hex[:10]}"
    (tmp_path / f"{module}.py").write_text(CONTROLLER.format(on_import=on_import))
    robot = dict(PLAIN["robots"][0], controller={
        "type": "python", "class_path": f"{module}:User", "params": {"where": where}})
    data = dict(PLAIN, robots=[robot])
    if expect:
        data["expect"] = {"r": {"max_collisions": 0}}
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return path, module


@pytest.mark.parametrize("on_import, where", [("sys.exit(7)", "none"), ("", "exit-init")])
def test_sys_exit_in_user_code_is_a_controller_failure(tmp_path, capsys, on_import, where):
    path, module = project(tmp_path, on_import, where)
    assert main(["run", str(path), "--headless"]) == 1
    err = capsys.readouterr().err
    assert f"error: controller {module}:User" in err and "SystemExit" in err


@pytest.mark.parametrize("on_import, where, what", [
    ("while True: pass", "none", "importing"),
    ("", "init", "its constructor"),
    ("", "compute", "compute()"),
])
def test_a_call_past_its_budget_fails_the_run_naming_the_controller(
        tmp_path, capsys, monkeypatch, on_import, where, what):
    monkeypatch.setenv(CALL_BUDGET_ENV, "0.3")
    path, module = project(tmp_path, on_import, where)
    started = time.process_time()  # CPU time: the spinning call is stopped, whatever the load
    assert main(["run", str(path), "--headless"]) == 1
    assert time.process_time() - started < 10
    err = capsys.readouterr().err
    assert f"error: controller {module}:User: {what}" in err and "0.3 s" in err
    assert CALL_BUDGET_ENV in err


def test_pymunk_bot_test_gives_user_code_a_budget_and_goes_on(tmp_path, capsys, monkeypatch):
    import pymunk_bot.controllers.python as python

    monkeypatch.delenv(CALL_BUDGET_ENV, raising=False)
    monkeypatch.setattr(python, "BATCH_CALL_BUDGET", 0.3)
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    stuck, module = project(tmp_path / "a", where="compute", expect=True)
    fine, _ = project(tmp_path / "b", expect=True)
    assert main(["test", str(stuck), str(fine), "--jobs", "1"]) == 1
    captured = capsys.readouterr()
    assert f"controller {module}:User: compute() took longer than 0.3 s" in captured.out
    assert "1 passed, 1 failed" in captured.out
    assert "[1/2]" in captured.err and "[2/2]" in captured.err  # progress as each one finishes
    assert CALL_BUDGET_ENV not in os.environ  # set for the command only


def test_interactive_runs_and_the_api_have_no_budget(monkeypatch):
    monkeypatch.delenv(CALL_BUDGET_ENV, raising=False)
    assert call_budget() is None
    with batch_budget():
        assert call_budget() == 10.0
    assert call_budget() is None
    monkeypatch.setenv(CALL_BUDGET_ENV, "0")
    assert call_budget() is None


def test_the_budget_holds_in_other_threads_too(monkeypatch):
    monkeypatch.setenv(CALL_BUDGET_ENV, "0.2")
    caught = []

    def spin() -> None:
        try:
            with budgeted("mod:Ctl", "compute()"):
                while True:
                    pass
        except ControllerError as exc:
            caught.append(str(exc))

    worker = threading.Thread(target=spin)
    worker.start()
    worker.join(timeout=HANG_GUARD)
    assert not worker.is_alive() and caught and caught[0].startswith("mod:Ctl: compute() took")


def test_a_sweep_in_worker_processes_names_the_controller_that_overran(tmp_path, capsys,
                                                                        monkeypatch):
    monkeypatch.setenv(CALL_BUDGET_ENV, "0.3")
    path, module = project(tmp_path, where="compute")
    monkeypatch.chdir(tmp_path)  # sweep looks for user modules in the current folder only
    code = main(["sweep", str(path), "--seeds", "0:2", "--backend", "process", "--workers", "1",
                 "--out", str(tmp_path / "rows.csv"), "--no-progress"])
    err = capsys.readouterr().err
    assert code != 0 and f"{module}:User: compute() took longer than 0.3 s" in err
    assert "BrokenProcessPool" not in err


def test_run_set_still_finds_the_controller_next_to_the_scenario(tmp_path, monkeypatch):
    path, _ = project(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["run", str(path), "--headless", "--set", "world.duration=0.5"]) == 0
