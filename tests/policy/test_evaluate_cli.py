"""`pymunk-bot evaluate POLICY SCENARIO --episodes N`: rates with confidence intervals."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("gymnasium")

from pymunk_bot.envs.evaluation import EpisodeOutcome, summarize, wilson  # noqa: E402
from pymunk_bot.policy.files import MlpPolicy  # noqa: E402
from command import pymunk_bot

BEAMS = 12


def homing(tmp_path, beams=BEAMS):
    """A linear policy that ignores the LiDAR: full speed, turning toward the goal bearing."""
    w = np.zeros((beams + 8, 2))
    w[beams + 5, 1] = 2.0
    MlpPolicy([w], [np.array([0.7, 0.0])]).save(tmp_path / "p.npz")
    scenario = {"name": "open", "world": {"size": [6.0, 5.0], "duration": 12.0},
                "obstacles": [{"type": "box", "center": [5.0, 4.0], "size": [0.4, 0.4]}],
                "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0],
                            "lidar": {"beams": beams, "max_range": 4.0},
                            "goal": {"position": [4.0, 2.5], "tolerance": 0.2}}]}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(scenario))
    return tmp_path / "p.npz", tmp_path / "s.yaml"


ROOT = Path(__file__).resolve().parents[2]


def test_evaluate_prints_rates_with_intervals_and_writes_episodes(tmp_path):
    policy, scenario = homing(tmp_path)
    out = pymunk_bot("evaluate", policy, scenario, "--episodes", "6", "--random-goal",
                  "--random-start", "--out", tmp_path / "e.csv", "--json")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    assert summary["episodes"] == 6
    assert 0.5 <= summary["reached"]["rate"] <= 1.0  # homing reaches most random goals
    assert summary["success"]["low"] <= summary["success"]["rate"] <= summary["success"]["high"]
    rows = list(csv.DictReader((tmp_path / "e.csv").open()))
    assert [int(r["seed"]) for r in rows] == list(range(6))
    assert sum(r["success"] == "True" for r in rows) == round(6 * summary["success"]["rate"])
    again = pymunk_bot("evaluate", policy, scenario, "--episodes", "6", "--random-goal",
                    "--random-start", "--json", "--workers", "2")
    assert json.loads(again.stdout) == summary  # the same episodes on two processes


def test_a_policy_for_another_lidar_is_one_line_exit_2(tmp_path):
    policy, scenario = homing(tmp_path, beams=20)
    scenario.write_text(scenario.read_text().replace("beams: 20", "beams: 12"))
    out = pymunk_bot("evaluate", policy, scenario, "--episodes", "2")
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and "takes 28 inputs" in out.stderr
    out = pymunk_bot("evaluate", tmp_path / "missing.npz", scenario)
    assert out.returncode == 2 and "no such file" in out.stderr


def test_summary_intervals():
    runs = [EpisodeOutcome(k, True, k % 4 != 0, 0.0 if k % 4 else 0.3, int(k % 4 == 0),
                           5.0 + k % 3, 1.0) for k in range(40)]
    s = summarize(runs)
    assert s["success"]["rate"] == 0.75 and s["contact"]["rate"] == 0.25
    assert (s["success"]["low"], s["success"]["high"]) == pytest.approx(wilson(30, 40))
    assert 0.59 < s["success"]["low"] < 0.75 < s["success"]["high"] < 0.87
    assert s["time_to_goal"]["mean"] == pytest.approx(np.mean([5.0 + k % 3 for k in range(40)]))


def test_the_shipped_policy_on_its_shipped_scenario_from_another_folder(tmp_path):
    # The scenario names its policy relative to its own folder, not the current one.
    out = pymunk_bot("evaluate", ROOT / "scenarios" / "policies" / "clutter_es.npz", "policy_clutter",
                  "--episodes", "2", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["reached"]["rate"] == 1.0


def test_generated_worlds_take_the_size_asked_for():
    import argparse

    from pymunk_bot.cli.evaluate import add_parser, env_kwargs
    from pymunk_bot.envs import NavigationEnv

    parser = argparse.ArgumentParser()
    add_parser(parser.add_subparsers())
    args = parser.parse_args(["evaluate", "p.npz", "policy_clutter", "--generate", "clutter",
                              "--size", "8", "6", "--world-seeds", "1000000:2000000"])
    env = NavigationEnv(**env_kwargs(args))
    env.reset(seed=3)
    assert env.sim is not None and env.sim.config.world.size == (8.0, 6.0)


def test_size_without_generate_is_one_line_exit_2(tmp_path):
    policy, scenario = homing(tmp_path)
    out = pymunk_bot("evaluate", policy, scenario, "--size", "8", "6")
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        "error: --size: applies to generated worlds: add --generate KIND"]
