"""What a run learns is told: controller failures, nothing checked, undecided, exit codes."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml

from pymunk_bot import Simulation
from pymunk_bot.cli import main

REPO = Path(__file__).resolve().parents[2]


def write(tmp_path: Path, data: dict, name: str = "s.yaml") -> str:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return str(path)


def test_a_controller_that_fails_is_exit_1_with_its_message(tmp_path, capsys):
    walled = {"name": "walled", "world": {"size": [6.0, 4.0], "duration": 2.0},
              "obstacles": [{"type": "wall", "start": [3.0, 0.0], "end": [3.0, 4.0],
                             "thickness": 0.2}],
              "robots": [{"name": "r", "pose": [1.0, 2.0, 0.0], "goal": {"position": [5.0, 2.0]},
                          "controller": {"type": "navigate"}}]}
    out_json = tmp_path / "r.json"
    assert main(["run", write(tmp_path, walled), "--headless", "--out", str(out_json)]) == 1
    out = capsys.readouterr().out
    assert "r: controller failed: no path" in out and out.rstrip().endswith("FAILED")
    result = json.loads(out_json.read_text())
    assert result["passed"] is False and result["verdict"] == "failed"


def test_a_run_with_no_expectations_says_nothing_was_checked(tmp_path, capsys):
    plain = {"name": "plain", "world": {"size": [4.0, 4.0], "duration": 1.0},
             "robots": [{"name": "r", "pose": [1.0, 1.0, 0.0]}]}
    assert main(["run", write(tmp_path, plain), "--headless"]) == 0
    out = capsys.readouterr().out
    assert "PASSED" not in out and "nothing checked" in out


def test_a_run_too_short_for_its_expectations_says_which_are_undecided(capsys):
    code = main(["run", str(REPO / "scenarios" / "open_goal.yaml"), "--headless",
                 "--duration", "1"])
    out = capsys.readouterr().out
    assert code == 1 and "FAILED" not in out
    assert "[undecided]" in out and "UNDECIDED: r1.goal_reached" in out
    assert "max_collisions" in out and "[ok]" in out  # what could be checked, was


def test_a_passing_run_says_how_many_expectations_it_checked(capsys):
    assert main(["run", str(REPO / "scenarios" / "open_goal.yaml"), "--headless"]) == 0
    assert "PASSED (" in capsys.readouterr().out


def test_a_closed_waypoint_route_is_driven_not_reported_done_at_once():
    data = {"name": "loop", "world": {"size": [4.0, 4.0]},
            "robots": [{"name": "r", "pose": [1.0, 1.0, 0.0], "controller": {
                "type": "waypoints", "points": [[3, 1], [3, 3], [1, 3], [1, 1]]}}]}
    sim = Simulation.from_dict(data)
    sim.run(1.0)
    robot = sim.robots["r"]
    assert robot.controller.status == "running" and robot.distance > 0.3
    sim.run(19.0)
    assert robot.controller.status == "arrived"
    assert robot.distance > 6.5  # the square is 8 m less its rounded corners
    assert math.dist(robot.pose[:2], (1.0, 1.0)) < 0.2


@pytest.mark.parametrize("size, offset", [((10.0, 6.0), 0.0), ((9.0, 5.0), 0.2)])
def test_two_navigate_robots_swap_head_on_without_touching(size, offset):
    w, h = size
    lidar = {"beams": 180, "max_range": 5.0, "noise_std": 0.01}
    data = {"name": "swap", "world": {"size": [w, h]}, "robots": [
        {"name": "a", "pose": [1.0, h / 2, 0.0], "lidar": lidar,
         "controller": {"type": "navigate"}, "goal": {"position": [w - 1.0, h / 2 + offset]}},
        {"name": "b", "pose": [w - 1.0, h / 2 + offset, math.pi], "lidar": lidar,
         "controller": {"type": "navigate"}, "goal": {"position": [1.0, h / 2]}}]}
    sim = Simulation.from_dict(data)
    sim.run(16.0)
    for robot in sim.robots.values():
        assert robot.goal_reached and robot.collisions == 0, robot.name


def test_an_internal_error_is_exit_3_with_its_traceback(tmp_path, capsys, monkeypatch):
    def broken(self, duration):
        raise RuntimeError("a bug inside the simulator")

    monkeypatch.setattr(Simulation, "run", broken)
    plain = {"name": "plain", "world": {"size": [4.0, 4.0]},
             "robots": [{"name": "r", "pose": [1.0, 1.0, 0.0]}]}
    assert main(["run", write(tmp_path, plain), "--headless"]) == 3
    err = capsys.readouterr().err
    assert "Traceback" in err and "internal error: RuntimeError: a bug inside" in err


def test_pursuit_gains_default_to_the_scenario_pursuit_defaults():
    from dataclasses import fields

    from pymunk_bot.config.controllers import PursuitConfig
    from pymunk_bot.planning.pursuit import PursuitGains

    gains = PursuitGains()
    shared = {f.name for f in fields(PursuitGains)} & set(PursuitConfig.model_fields)
    assert shared >= {"lookahead", "lookahead_time", "corner_radius", "decel"}
    for name in shared:
        assert getattr(gains, name) == PursuitConfig.model_fields[name].default, name


def test_a_controller_failure_the_scenario_expects_is_not_a_failure(capsys):
    # unreachable.yaml expects goal_reached: false, i.e. that navigate gives up cleanly.
    assert main(["run", str(REPO / "scenarios" / "unreachable.yaml"), "--headless"]) == 0
    assert "PASSED" in capsys.readouterr().out


def test_the_printed_heading_is_wrapped_and_the_json_keeps_the_turns(tmp_path, capsys):
    """A robot that spun one and a half turns reads 9.7 rad in the JSON (unwrapped, as
    documented), but the summary a person reads says where it points: within [-pi, pi)."""
    spin = {"name": "spin", "world": {"size": [4.0, 4.0], "duration": 3.0},
            "robots": [{"name": "r1", "pose": [2.0, 2.0, 0.0],
                        "controller": {"type": "wheels", "left": -0.5, "right": 0.5}}]}
    out_json = tmp_path / "r.json"
    main(["run", write(tmp_path, spin), "--headless", "--out", str(out_json)])
    theta = json.loads(out_json.read_text())["robots"]["r1"]["pose"][2]
    assert theta > 2 * math.pi  # the run really turned more than once
    line = next(line for line in capsys.readouterr().out.splitlines() if "r1: pose (" in line)
    printed = float(line.split("pose (")[1].split(")")[0].split(", ")[2])
    assert -math.pi <= printed < math.pi
    assert printed == pytest.approx(math.remainder(theta, 2 * math.pi), abs=1e-3)
