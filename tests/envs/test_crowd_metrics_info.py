"""A crowd scenario in the Gymnasium and PettingZoo envs: the episode's navigation metrics
(docs/benchmark.md) come in ``info["metrics"]`` when it ends."""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.envs import MultiRobotEnv, NavigationEnv
from pymunk_bot.outcomes.navigation import METRIC_NAMES

CROWD = {
    "name": "crowd_env", "world": {"size": [8.0, 4.0], "duration": 3.0},
    "obstacles": [{"type": "pedestrian", "center": [6.0, 2.0], "goals": [[1.0, 2.0]],
                   "policy": "orca"}],
    "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0], "goal": {"position": [7.0, 1.0]},
                "lidar": {"beams": 36, "max_range": 5.0}},
               {"name": "r2", "pose": [1.0, 3.0, 0.0], "goal": {"position": [7.0, 3.0]},
                "lidar": {"beams": 36, "max_range": 5.0}}],
}


def test_the_env_reports_the_navigation_metrics_when_a_crowd_episode_ends():
    env = NavigationEnv(CROWD, max_episode_time=2.0)
    env.reset(seed=1)
    info: dict = {}
    done = False
    while not done:
        _, _, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
        done = terminated or truncated
        if not done:
            assert "metrics" not in info  # only when the episode ends
    metrics = info["metrics"]
    assert set(METRIC_NAMES) <= set(metrics)
    assert metrics["path_length"] > 1.0  # it drove forward for 2 s
    assert math.isfinite(metrics["min_distance_to_human"])


def test_the_pettingzoo_env_reports_each_agents_metrics():
    env = MultiRobotEnv(CROWD, max_episode_time=1.0)
    env.reset(seed=2)
    ended: dict = {}
    while env.agents:
        actions = {a: np.array([0.5, 0.0], np.float32) for a in env.agents}
        _, _, terminations, truncations, infos = env.step(actions)
        for agent in actions:
            if terminations[agent] or truncations[agent]:
                ended[agent] = infos[agent]["metrics"]
    assert set(ended) == {"r1", "r2"}
    assert all(m["path_length"] > 0.2 for m in ended.values())
