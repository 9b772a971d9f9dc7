"""Crowd layouts drawn per episode (``randomize={"crowd": SUITE}``): each episode one of the
suite's scenarios with its CrowdNav layout drawn from the episode's seed."""
from __future__ import annotations

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from pymunk_bot.envs import NavigationEnv, NavigationVectorEnv  # noqa: E402
from pymunk_bot.config.errors import ScenarioError  # noqa: E402

ROBOT = {"name": "me", "pose": [1.0, 1.0, 0.0], "radius": 0.2,
         "lidar": {"beams": 24, "max_range": 5.0}, "goal": {"position": [3.0, 3.0]}}
BASE = {"name": "learner", "world": {"size": [6.0, 5.0], "duration": 5.0}, "robots": [ROBOT]}
SPEC = {"suite": "tiny", "duration": 5.0, "stage": 6.0,
        "robot": {"name": "r1", "radius": 0.2, "lidar": {"beams": 36, "max_range": 6.0}},
        "pedestrian": {"speed": 1.0},
        "worlds": {"open": {"size": [8.0, 8.0]},
                   "cluttered": {"generate": "clutter", "seed": 1, "size": [10.0, 10.0]}},
        "layouts": ["circle_crossing", "doorway"], "densities": {"few": 3}}


@pytest.fixture
def suite(tmp_path):
    import yaml

    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(SPEC))
    return str(path)


def episode(env, seed: int) -> tuple:
    env.reset(seed=seed)
    sim = env.unwrapped.sim
    walkers = sorted(tuple(o.center) for o in sim.config.obstacles if o.type == "pedestrian")
    robot = sim.robots["me"]
    return (sim.world.width, tuple(walkers), tuple(np.round(robot.pose, 6)), tuple(robot.goal),
            len(sim.config.obstacles))


def test_each_episode_draws_a_layout_of_the_suite_and_a_seed_repeats_it(suite):
    env = NavigationEnv(BASE, randomize={"crowd": suite})
    episodes = [episode(env, seed) for seed in range(6)]
    assert episode(env, 3) == episodes[3]  # the same seed, the same episode
    assert len(set(episodes)) == 6  # new layouts every episode
    assert {e[0] for e in episodes} == {8.0, 10.0}  # from both of the suite's worlds
    for width, walkers, pose, goal, _ in episodes:
        assert len(walkers) == 3  # the density's pedestrians
        assert np.hypot(goal[0] - pose[0], goal[1] - pose[1]) > 2.0  # across the stage
    robot = env.unwrapped.sim.robots["me"]
    assert robot.config.lidar.beams == 24  # the env's learning robot, in the drawn layout
    obs, *_ = env.step(env.action_space.sample())
    assert obs.shape == env.observation_space.shape


def test_the_vector_env_slots_play_the_single_envs_crowd_episodes(suite):
    envs = NavigationVectorEnv(num_envs=2, scenario=BASE, randomize={"crowd": suite})
    single = NavigationEnv(BASE, randomize={"crowd": suite})
    obs, _ = envs.reset(seed=10)
    for i in range(2):
        single_obs, _ = single.reset(seed=10 + i)
        np.testing.assert_array_equal(obs[i], single_obs)
        assert [o.model_dump() for o in envs.episodes[i].sim.config.obstacles] == \
            [o.model_dump() for o in single.unwrapped.sim.config.obstacles]


@pytest.mark.parametrize("randomize, message", [
    ({"crowd": "no_such_suite"}, "randomize.crowd: no_such_suite"),
    ({"crowd": 3}, "must name a suite"),
    ({"crowd": "crowds", "generate": "clutter"}, "leave out randomize.generate"),
])
def test_a_bad_crowd_suite_is_one_line_naming_the_key(randomize, message):
    with pytest.raises(ScenarioError, match=message) as info:
        NavigationEnv(BASE, randomize=randomize)
    assert "randomize.crowd" in str(info.value) and "\n" not in str(info.value)
