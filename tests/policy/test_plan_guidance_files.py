"""A policy file trained with plan guidance records it; evaluate and the policy controller turn
it on from the file; a mismatch, or guidance with no map to plan on, is one line, exit 2."""
from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

pytest.importorskip("gymnasium")

from pymunk_bot.config.guidance import PlanGuidanceConfig  # noqa: E402
from pymunk_bot.envs.evaluation import run_episodes  # noqa: E402
from pymunk_bot.policy.files import MlpPolicy, PolicyFileError, load_policy  # noqa: E402
from command import pymunk_bot

BEAMS = 12


def homing(guidance: PlanGuidanceConfig | None) -> MlpPolicy:
    """A linear policy that ignores the LiDAR: full speed, turning toward the goal bearing."""
    w = np.zeros((BEAMS + 8, 2))
    w[BEAMS + 5, 1] = 2.0
    return MlpPolicy([w], [np.array([0.7, 0.0])], guidance)


def two_rooms(controller: dict | None = None, **robot_keys) -> dict:
    """A wall at x = 4 m splits the arena; the door is above y = 4.5 m."""
    robot = {"name": "r1", "pose": [2.0, 1.0, 0.0], "lidar": {"beams": BEAMS, "max_range": 4.0},
             "goal": {"position": [6.0, 1.0], "tolerance": 0.3}, **robot_keys}
    if controller is not None:
        robot["controller"] = controller
    return {"name": "two_rooms", "world": {"size": [8.0, 6.0], "duration": 40.0},
            "obstacles": [{"type": "wall", "start": [4.0, 0.0], "end": [4.0, 4.5],
                           "thickness": 0.1}],
            "robots": [robot]}


def write(tmp_path, data: dict, name: str = "s.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_npz_records_the_settings_it_was_trained_with(tmp_path):
    settings = PlanGuidanceConfig(lookahead=2.0, replan_period=0.5)
    homing(settings).save(tmp_path / "guided.npz")
    homing(None).save(tmp_path / "plain.npz")
    assert load_policy(tmp_path / "guided.npz").plan_guidance == settings
    assert load_policy(tmp_path / "plain.npz").plan_guidance is None
    with np.load(tmp_path / "guided.npz") as arrays:
        assert arrays["plan_guidance"].tolist() == settings.as_array()


@pytest.mark.parametrize("record, words", [
    ([1.0, 2.0], "plan_guidance holds 2 numbers, not 4"),
    ([-1.0, 1.0, 1.0, 0.1], "lookahead"),
])
def test_a_malformed_record_is_refused(tmp_path, record, words):
    policy = homing(None)
    np.savez(tmp_path / "p.npz", W0=policy.weights[0], b0=policy.biases[0],
             plan_guidance=np.array(record))
    with pytest.raises(PolicyFileError, match=words) as caught:
        load_policy(tmp_path / "p.npz")
    assert "\n" not in str(caught.value)


def test_evaluate_turns_guidance_on_from_the_file(tmp_path):
    homing(PlanGuidanceConfig()).save(tmp_path / "guided.npz")
    homing(None).save(tmp_path / "plain.npz")
    scenario = write(tmp_path, two_rooms())
    reached = {}
    for name in ("guided", "plain"):
        out = pymunk_bot("evaluate", tmp_path / f"{name}.npz", scenario, "--episodes", "2",
                         "--max-time", "30", "--json")
        assert out.returncode == 0, out.stderr
        reached[name] = json.loads(out.stdout)["reached"]["rate"]
    # Steering at the goal's bearing, the plain policy stays pressed against the wall; steering
    # at the guided goal's, it drives out through the door and arrives.
    assert reached == {"guided": 1.0, "plain": 0.0}


def test_evaluate_refuses_guidance_for_a_policy_trained_without(tmp_path):
    homing(None).save(tmp_path / "plain.npz")
    out = pymunk_bot("evaluate", tmp_path / "plain.npz", write(tmp_path, two_rooms()),
                     "--episodes", "1", "--plan-guidance")
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "trained without plan guidance" in lines[0]


def test_an_env_without_guidance_refuses_a_guided_policy(tmp_path):
    homing(PlanGuidanceConfig()).save(tmp_path / "guided.npz")
    with pytest.raises(PolicyFileError, match="trained with plan guidance"):
        run_episodes(tmp_path / "guided.npz", {"scenario": two_rooms()}, [0])
    homing(None).save(tmp_path / "plain.npz")
    with pytest.raises(PolicyFileError, match="trained without plan guidance"):
        run_episodes(tmp_path / "plain.npz", {"scenario": two_rooms(), "plan_guidance": True},
                     [0])


@pytest.mark.parametrize("policy, controller_keys, robot_keys, words", [
    ("guided", {}, {"localization": "slam"},
     "robots[0].controller.plan_guidance: plan guidance plans on the map the robot is given, "
     "and localization 'slam' starts with none: set robots[0].localization"),
    ("plain", {"plan_guidance": {"slam_map": True}}, {}, "plan_guidance"),
    ("guided", {"plan_guidance": False}, {}, "robots[0].controller: 'p.npz' was trained with "
                                             "plan guidance"),
    ("plain", {"plan_guidance": True}, {}, "robots[0].controller: 'p.npz' was trained without "
                                           "plan guidance"),
    ("guided", {"plan_guidance": {"resolution": 0.02}}, {}, "plan_guidance.resolution"),
])
def test_bad_guidance_in_a_scenario_is_one_line_exit_2(tmp_path, policy, controller_keys,
                                                       robot_keys, words):
    homing(PlanGuidanceConfig() if policy == "guided" else None).save(tmp_path / "p.npz")
    data = two_rooms({"type": "policy", "path": "p.npz", **controller_keys}, **robot_keys)
    if "resolution" in str(controller_keys):
        data["world"]["size"] = [500.0, 500.0]  # 625 million cells at 2 cm
    out = pymunk_bot("validate", write(tmp_path, data))
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], lines
    assert "Traceback" not in out.stderr


def test_the_controller_turns_guidance_on_from_the_file(tmp_path):
    homing(PlanGuidanceConfig()).save(tmp_path / "p.npz")
    path = write(tmp_path, two_rooms({"type": "policy", "path": "p.npz"},
                                     localization="ground_truth"))
    out = pymunk_bot("run", path, "--headless", "--duration", "30", "--out", tmp_path / "r.json")
    assert out.returncode == 0, out.stderr
    robot = json.loads((tmp_path / "r.json").read_text())["robots"]["r1"]
    assert robot["goal_reached"] and robot["controller_status"] == "arrived"
