"""kept_env: one env per process and arguments, reused by a trainer's jobs wherever they run;
an episode in it depends on its seed only, not on what the env played before."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from pymunk_bot.envs.evaluation import MAX_KEPT_ENVS, kept_env, release_kept_envs, \
    run_episodes  # noqa: E402
from pymunk_bot.policy.files import MlpPolicy  # noqa: E402

ROBOT = {"name": "r1", "pose": [1.0, 1.0, 0.0], "radius": 0.2,
         "lidar": {"beams": 8, "max_range": 3.0}, "goal": {"position": [2.0, 2.0]}}
KWARGS = {"scenario": {"name": "kept", "world": {"size": [6.0, 5.0]}, "robots": [ROBOT]},
          "random_goal": True, "max_episode_time": 3.0,
          "randomize": {"generate": "clutter", "size": [6.0, 5.0], "world_seeds": [0, 20],
                        "start": True}}


def test_the_same_arguments_get_the_same_env_and_the_number_kept_is_bounded():
    release_kept_envs()
    env = kept_env(KWARGS)
    assert kept_env({**KWARGS}) is env
    more = [{**KWARGS, "max_episode_time": 10.0 + k} for k in range(MAX_KEPT_ENVS)]
    others = [kept_env(kwargs) for kwargs in more]
    assert kept_env(more[-1]) is others[-1]
    assert kept_env(KWARGS) is not env  # the oldest made room for the others: made anew
    release_kept_envs()


def test_an_episode_in_a_kept_env_is_the_one_a_new_env_plays():
    env = kept_env(KWARGS)
    inputs = env.observation_space.shape[0]
    rng = np.random.default_rng(0)
    policy = MlpPolicy([rng.normal(0, 0.5, (inputs, 2))], [np.array([0.6, 0.0])])
    after_others = run_episodes(policy, None, [11, 12, 13], env=env)[-1]
    fresh = run_episodes(policy, KWARGS, [13])[0]
    assert after_others == fresh
    assert fresh.episode_return != 0.0
    release_kept_envs()
