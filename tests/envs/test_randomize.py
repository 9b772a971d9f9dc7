"""Domain randomization (``randomize=``) and the vector env's finished slots."""
from __future__ import annotations

import math

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from gymnasium.vector import AutoresetMode  # noqa: E402

from pymunk_bot.envs import NavigationEnv, NavigationVectorEnv  # noqa: E402
from pymunk_bot.config.errors import ScenarioError  # noqa: E402

ROBOT = {"name": "r1", "pose": [1.0, 1.0, 0.0], "radius": 0.2,
         "lidar": {"beams": 16, "max_range": 4.0}, "goal": {"position": [3.0, 3.0]}}
BASE = {"name": "base", "world": {"size": [6.0, 5.0], "duration": 5.0}, "robots": [ROBOT]}
CLUTTER = {"generate": "clutter", "size": [8.0, 6.0], "world_seeds": [0, 50], "start": True}


def obstacles(env) -> list:
    return [o.model_dump() for o in env.sim.config.obstacles]


def test_every_episode_is_a_new_generated_world_and_start_repeatable_by_seed():
    env = NavigationEnv(BASE, randomize=CLUTTER, random_goal=True)
    worlds, starts = [], []
    for seed in (1, 2, 1):
        env.reset(seed=seed)
        worlds.append(obstacles(env))
        starts.append(tuple(env.sim.robots["r1"].pose))
    assert worlds[0] == worlds[2] and starts[0] == starts[2]  # a seed gives the same episode
    assert worlds[0] != worlds[1] and starts[0] != starts[1]
    assert env.sim.world.width == 8.0 and len(worlds[0]) > 5  # the generated clutter
    robot = env.sim.robots["r1"]
    assert robot.config.lidar.beams == 16  # the scenario's robot, in the generated world
    import pymunk

    hits = env.sim.world.space.point_query(tuple(robot.pose[:2]), robot.radius + 0.1,
                                           pymunk.ShapeFilter())
    assert all(h.shape.body is robot.body for h in hits)  # started clear of everything


def test_scenario_keys_are_drawn_within_their_ranges_and_choices():
    env = NavigationEnv(BASE, randomize={"set": {
        "robots[0].max_wheel_speed": [0.3, 0.9],
        "robots[0].lidar.noise_std": {"choices": [0.0, 0.05]}}})
    speeds, noises = set(), set()
    for seed in range(12):
        env.reset(seed=seed)
        config = env.sim.robots["r1"].config
        speeds.add(config.max_wheel_speed)
        noises.add(config.lidar.noise_std)
        assert env.episode.task.v_max == config.max_wheel_speed  # the action scales with it
    assert all(0.3 <= s <= 0.9 for s in speeds) and len(speeds) == 12
    assert noises == {0.0, 0.05}


@pytest.mark.parametrize("randomize, path", [
    ({"generate": "forest"}, "randomize.generate"),
    ({"colour": 1}, "randomize.colour"),
    ({"set": {"robots[0].max_wheel_speed": [0.5, -1.0]}}, "randomize.set.robots[0].max_wheel_speed"),
    ({"set": {"robots[0].max_wheel_speed": [-1.0, 0.5]}}, "randomize.set.robots[0].max_wheel_speed"),
    ({"set": {"robots[3].radius": [0.1, 0.2]}}, "randomize.set.robots[3]"),
    ({"set": {"robots[0].lidar.beams": {"choices": []}}}, "randomize.set.robots[0].lidar.beams"),
    ({"world_seeds": [5, 5]}, "randomize.world_seeds"),
])
def test_bad_randomization_names_the_key(randomize, path):
    with pytest.raises(ScenarioError) as err:
        NavigationEnv(BASE, randomize=randomize)
    assert err.value.path == path or str(err.value.path).startswith(path)


def test_a_draw_may_not_change_the_observation_size():
    env = NavigationEnv(BASE, randomize={"set": {"robots[0].lidar.beams": {"choices": [16, 32]}}})
    with pytest.raises(ScenarioError, match="observation's size"):
        for seed in range(10):
            env.reset(seed=seed)


def test_vector_slots_play_the_single_env_randomized_episodes():
    kwargs = {"scenario": BASE, "randomize": CLUTTER, "random_goal": True,
              "max_episode_time": 1.0}
    envs = NavigationVectorEnv(num_envs=3, **kwargs)
    obs, _ = envs.reset(seed=20)
    single = NavigationEnv(**kwargs)
    actions = np.random.default_rng(0).uniform(-1, 1, (5, 3, 2)).astype(np.float32)
    for i in range(3):
        expected = single.reset(seed=20 + i)[0]
        np.testing.assert_array_equal(obs[i], expected)
    vec = [envs.step(a)[0] for a in actions]
    for i in range(3):
        single.reset(seed=20 + i)
        for k in range(5):
            np.testing.assert_array_equal(vec[k][i], single.step(actions[k, i])[0])


def test_disabled_autoreset_leaves_finished_slots_unstepped():
    short = {"name": "short", "world": {"size": [4.0, 3.0], "duration": 3.0},
             "robots": [{"name": "r1", "pose": [1.0, 1.5, 0.0], "lidar": {"beams": 12},
                         "goal": {"position": [1.6, 1.5], "tolerance": 0.1}}]}
    envs = NavigationVectorEnv(num_envs=2, scenario=short, autoreset_mode=AutoresetMode.DISABLED)
    envs.reset(seed=0)
    go_and_stay = np.array([[1.0, 0.0], [0.0, 0.0]], np.float32)
    for _ in range(15):
        obs, rewards, terminated, truncated, info = envs.step(go_and_stay)
        if terminated[0]:
            break
    assert terminated[0]
    final, pose = obs[0].copy(), envs.episodes[0].sim.robots["r1"].pose
    for _ in range(5):  # slot 0 waits for its reset; slot 1 goes on
        obs, rewards, terminated, truncated, info = envs.step(np.ones((2, 2), np.float32))
        assert rewards[0] == 0.0 and not terminated[0] and not truncated[0]
        np.testing.assert_array_equal(obs[0], final)
    robot = envs.episodes[0].sim.robots["r1"]
    assert np.hypot(*(robot.pose[:2] - pose[:2])) < 0.25 and math.isclose(
        robot.velocity[0], 0.0, abs_tol=0.05)  # braked to a stop (0.5 s at 1 m/s: 0.5 m)
    assert envs.episodes[1].sim.robots["r1"].velocity[0] > 0.3
    obs, _ = envs.reset(options={"reset_mask": np.array([True, False])})
    assert not envs.episodes[0].done and obs[0, 12 + 3] == pytest.approx(0.6 / 1.6, abs=1e-6)
