"""The native vector env (lockstep, autoreset) and the PettingZoo multi-robot env."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import pymunk_bot.envs  # noqa: E402,F401
from pymunk_bot.envs import NavigationEnv, NavigationVectorEnv  # noqa: E402
from gymnasium.vector import AutoresetMode  # noqa: E402
from bounds import HANG_GUARD


def short_task(duration=0.5) -> dict:
    """Goal 0.6 m straight ahead: full speed reaches it in about 0.6 s."""
    return {"name": "short", "world": {"size": [4.0, 3.0], "duration": duration},
            "robots": [{"name": "r1", "pose": [1.0, 1.5, 0.0],
                        "lidar": {"beams": 12, "max_range": 5.0, "noise_std": 0.01},
                        "goal": {"position": [1.6, 1.5], "tolerance": 0.1}}]}


def test_make_vec_uses_the_native_vector_env():
    envs = gym.make_vec("pymunk_bot/Navigation-v0", num_envs=3,
                        vectorization_mode="vector_entry_point", lidar={"beams": 30})
    assert isinstance(envs.unwrapped, NavigationVectorEnv)
    obs, info = envs.reset(seed=5)
    assert obs.shape == (3, 30 + 8) and obs.dtype == np.float32
    assert envs.observation_space.contains(obs)
    obs, rewards, terminated, truncated, info = envs.step(envs.action_space.sample())
    assert rewards.shape == (3,) and terminated.dtype == np.bool_
    assert info["collisions"].shape == (3,)
    envs.close()


def test_slot_i_plays_the_single_env_episode_of_seed_plus_i():
    envs = NavigationVectorEnv(num_envs=3, scenario=short_task(duration=2.0))
    singles = [NavigationEnv(short_task(duration=2.0)) for _ in range(3)]
    obs, _ = envs.reset(seed=10)
    for i, env in enumerate(singles):
        np.testing.assert_array_equal(obs[i], env.reset(seed=10 + i)[0])
    actions = np.random.default_rng(1).uniform(-1, 1, size=(8, 3, 2)).astype(np.float32)
    for batch in actions:
        obs, rewards, *_ = envs.step(batch)
        for i, env in enumerate(singles):
            single_obs, reward, *_ = env.step(batch[i])
            np.testing.assert_array_equal(obs[i], single_obs)
            assert rewards[i] == reward


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_slots_play_single_env_episodes_across_autoresets(mode):
    """Episodes end at different steps (some slots reset while others step): every slot's
    observations and rewards are still its single env's, episode after episode."""
    envs = NavigationVectorEnv(num_envs=3, scenario=short_task(duration=0.8),
                               autoreset_mode=mode)
    singles = [NavigationEnv(short_task(duration=0.8)) for _ in range(3)]
    envs.reset(seed=3)
    for i, env in enumerate(singles):
        env.reset(seed=3 + i)
    rng = np.random.default_rng(2)
    ended = np.zeros(3, dtype=bool)
    resets = 0
    for _ in range(40):
        actions = rng.uniform(-0.2, 1.0, size=(3, 2)).astype(np.float32)
        obs, rewards, terminated, truncated, info = envs.step(actions)
        for i, env in enumerate(singles):
            if ended[i] and mode == AutoresetMode.NEXT_STEP:  # this step was slot i's reset
                expected, reward = env.reset()[0], 0.0
                resets += 1
            else:
                expected, reward, done, cut, single_info = env.step(actions[i])
                assert (done, cut) == (terminated[i], truncated[i])
                # SAME_STEP: an ended slot's info is its reset's, the step's is final_info.
                step_info = (info["final_info"] if mode == AutoresetMode.SAME_STEP
                             and (done or cut) else info)
                for key in ("distance_to_goal", "collisions", "new_collisions", "time"):
                    assert step_info[key][i] == single_info[key] and step_info[f"_{key}"][i]
                if done or cut:  # gymnasium nests a dict's fields as arrays
                    for key, value in single_info["result"].items():
                        assert step_info["result"][key][i] == value, key
                if mode == AutoresetMode.SAME_STEP and (done or cut):
                    np.testing.assert_array_equal(info["final_obs"][i], expected)
                    expected = env.reset()[0]
                    resets += 1
            np.testing.assert_array_equal(obs[i], expected)
            assert rewards[i] == reward
        ended = terminated | truncated
    assert resets >= 4


def test_next_step_autoreset_follows_gymnasium():
    envs = NavigationVectorEnv(num_envs=2, scenario=short_task(duration=1.0))
    envs.reset(seed=0)
    stop_and_go = np.array([[1.0, 0.0], [0.0, 0.0]], np.float32)
    history = [envs.step(stop_and_go) for _ in range(10)]  # 1 s of 0.1 s steps
    # Slot 0 drives to the goal (terminated), slot 1 stands still until the 1 s limit.
    k = next(i for i, h in enumerate(history) if h[2][0])
    assert k < 9 and history[k][4]["result"]["goal_reached"][0]
    assert history[9][3][1] and not history[9][2][1]
    obs, rewards, terminated, truncated, info = history[k + 1]  # slot 0's reset step
    assert rewards[0] == 0.0 and not terminated[0] and not truncated[0]
    assert info["_sim_seed"][0] and not info["_sim_seed"][1]  # only slot 0 was reset
    assert obs[0, 12 + 3] == pytest.approx(0.6 / 1.6, abs=1e-6)  # back at the start: d / (d + 1 m)
    assert (obs[0, 12 + 6:] == 0.0).all()  # no previous action after a reset


def test_same_step_autoreset_returns_the_final_observation():
    envs = NavigationVectorEnv(num_envs=1, scenario=short_task(duration=0.3),
                               autoreset_mode=AutoresetMode.SAME_STEP)
    envs.reset(seed=0)
    truncated = np.array([False])
    while not truncated[0]:
        obs, _, _, truncated, info = envs.step(np.zeros((1, 2), np.float32))
    assert info["_final_obs"][0] and info["final_info"]["time"][0] == pytest.approx(0.3)
    assert info["final_info"]["result"]["goal_reached"][0] is np.False_ or \
        not info["final_info"]["result"]["goal_reached"][0]
    assert envs.episodes[0].sim.time == 0.0  # already reset


def test_reset_mask_resets_only_the_chosen_slots():
    envs = NavigationVectorEnv(num_envs=2, scenario=short_task(duration=2.0))
    envs.reset(seed=0)
    envs.step(np.ones((2, 2), np.float32))
    envs.reset(options={"reset_mask": np.array([True, False])})
    assert envs.episodes[0].sim.time == 0.0 and envs.episodes[1].sim.time > 0.0


def test_vector_rgb_array_gives_one_frame_per_env():
    envs = NavigationVectorEnv(num_envs=2, scenario=short_task(), render_mode="rgb_array")
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2 and frames[0].dtype == np.uint8 and frames[0].shape[2] == 3
    envs.close()


def test_bad_num_envs_is_refused():
    with pytest.raises(ValueError):
        NavigationVectorEnv(num_envs=0)


# ---------------------------------------------------------------------------- PettingZoo

def test_multi_robot_env_passes_the_parallel_api_test():
    pytest.importorskip("pettingzoo")
    from pettingzoo.test import parallel_api_test

    from pymunk_bot.envs import MultiRobotEnv

    parallel_api_test(MultiRobotEnv("head_on_swap", lidar={"beams": 36}), num_cycles=100)


def test_multi_robot_env_with_no_scenario_has_several_agents_that_step():
    pytest.importorskip("pettingzoo")
    from pymunk_bot.envs import MultiRobotEnv

    env = MultiRobotEnv()  # the contract: a shipped scenario with at least two robots
    assert len(env.possible_agents) >= 2
    observations, _ = env.reset(seed=0)
    assert set(observations) == set(env.possible_agents)
    start = env.state().copy()
    for _ in range(5):
        observations, rewards, *_ = env.step({a: np.array([1.0, 0.0]) for a in env.agents})
    assert set(rewards) == set(env.possible_agents)
    assert np.abs(env.state() - start).max() > 0.05  # every agent's robot is driven


def two_robots() -> dict:
    return {"name": "pair", "world": {"size": [6.0, 4.0], "duration": 5.0},
            "robots": [{"name": "a", "pose": [1.0, 1.0, 0.0], "lidar": {"beams": 8},
                        "goal": {"position": [1.8, 1.0], "tolerance": 0.1}},
                       {"name": "b", "pose": [1.0, 3.0, 0.0], "lidar": {"beams": 8},
                        "goal": {"position": [5.0, 3.0], "tolerance": 0.1}}]}


def test_an_agent_that_arrives_leaves_and_its_robot_holds_still():
    pytest.importorskip("pettingzoo")
    from pymunk_bot.envs import MultiRobotEnv

    env = MultiRobotEnv(two_robots())
    obs, _ = env.reset(seed=0)
    assert env.agents == ["a", "b"] and obs["a"].shape == (8 + 8,)
    for _ in range(30):
        obs, rewards, terminations, truncations, infos = env.step(
            {a: np.array([1.0, 0.0], np.float32) for a in env.agents})
        if terminations.get("a"):
            break
    assert terminations["a"] and infos["a"]["result"]["goal_reached"]
    assert env.agents == ["b"]
    x_a = env.sim.robots["a"].pose[0]
    for _ in range(4):  # braking from 1 m/s at 3 m/s^2 takes 1/3 s and 1/6 m
        env.step({"b": np.array([1.0, 0.0], np.float32)})
    x_stopped = env.sim.robots["a"].pose[0]
    assert x_stopped - x_a == pytest.approx(1.0 / 6.0, abs=0.02)
    env.step({"b": np.array([1.0, 0.0], np.float32)})
    assert env.sim.robots["a"].pose[0] == pytest.approx(x_stopped, abs=1e-6)
    assert env.state().shape == (6,)


def test_the_worlds_share_spaces_and_advance_together():
    """Up to 16 worlds to a pymunk Space, every one a control period further per step."""
    from pymunk_bot.physics.settings import MAX_REPLICAS

    envs = NavigationVectorEnv(num_envs=MAX_REPLICAS + 4, scenario=short_task(duration=2.0))
    envs.reset(seed=0)
    envs.step(np.zeros((MAX_REPLICAS + 4, 2), np.float32))
    envs.step(np.zeros((MAX_REPLICAS + 4, 2), np.float32))
    spaces = {id(e.sim.world.space) for e in envs.episodes}
    assert len(spaces) == 2  # 20 worlds: two spaces of 10
    assert all(e.sim.time == pytest.approx(0.2) for e in envs.episodes)


def test_worlds_with_pedestrians_share_a_space():  # each copy's crowd keeps to its own
    scenario = short_task(duration=2.0)
    scenario["obstacles"] = [{"type": "pedestrian", "center": [3.0, 0.5], "goals": [[3.0, 2.5]]}]
    envs = NavigationVectorEnv(num_envs=2, scenario=scenario)
    envs.reset(seed=0)
    envs.step(np.zeros((2, 2), np.float32))
    assert envs.episodes[0].sim.world.space is envs.episodes[1].sim.world.space


def test_worlds_of_their_own_push_crates_exactly_as_single_envs():
    """share_space=False: each world in its own space, float for float the single env's
    episode, crate pushing included."""
    from pymunk_bot.config import load_scenario

    data = load_scenario(None).model_dump(exclude_unset=True)
    data["robots"][0]["pose"] = [4.0, 4.7, 0.0]  # the crate 1 m ahead
    envs = NavigationVectorEnv(num_envs=2, scenario=data, share_space=False)
    singles = [NavigationEnv(scenario=data) for _ in range(2)]
    obs, _ = envs.reset(seed=3)
    for i, env in enumerate(singles):
        np.testing.assert_array_equal(obs[i], env.reset(seed=3 + i)[0])
    assert envs.episodes[0].sim.world.space is not envs.episodes[1].sim.world.space
    actions = np.array([[0.6, 0.05], [0.5, -0.05]], np.float32)
    for _ in range(40):
        obs, rewards, *_ = envs.step(actions)
        for i, env in enumerate(singles):
            np.testing.assert_array_equal(obs[i], env.step(actions[i])[0])
    assert all(e.sim.world.obstacles[4].body.position.x > 5.1 for e in envs.episodes)  # pushed


@pytest.mark.parametrize("scenario, extra", [("floor_plan", {}),
                                             ("scenarios/mcl_office.yaml", {"random_goal": True})])
def test_envs_run_on_ros_map_scenarios(scenario, extra):
    """A scenario whose arena comes from a ROS map (`world.map`, no `size`): the single env and
    the vector env (its worlds sharing the map's geometry) drive in it."""
    env = NavigationEnv(scenario=scenario, lidar={"beams": 36}, **extra)
    obs, _ = env.reset(seed=0)
    envs = NavigationVectorEnv(num_envs=2, scenario=scenario, lidar={"beams": 36}, **extra)
    vec_obs, _ = envs.reset(seed=0)
    np.testing.assert_array_equal(vec_obs[0], obs)
    for _ in range(10):
        obs = env.step(np.array([0.5, 0.1], np.float32))[0]
        vec_obs = envs.step(np.array([[0.5, 0.1], [0.5, 0.1]], np.float32))[0]
    np.testing.assert_array_equal(vec_obs[0], obs)
    assert obs[:36].min() < 1.0  # the map's walls are in sight


VECTOR_SCRIPT = """
import hashlib, numpy as np
from pymunk_bot.config import load_scenario
from pymunk_bot.envs import NavigationVectorEnv
data = load_scenario(None).model_dump(exclude_unset=True)
data["robots"][0]["pose"] = [4.0, 4.7, 0.0]  # the crate 1 m ahead: contacts between movers
envs = NavigationVectorEnv(num_envs=3, scenario=data, lidar={"beams": 60})
h = hashlib.sha256()
obs, _ = envs.reset(seed=11)
h.update(obs.tobytes())
actions = np.random.default_rng(0).uniform(-0.2, 1, size=(40, 3, 2)).astype(np.float32)
for a in actions:
    obs, r, te, tr, info = envs.step(a)
    h.update(obs.tobytes()); h.update(r.tobytes())
print(h.hexdigest())
"""


def test_shared_space_worlds_are_identical_in_another_process():
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONHASHSEED": "321", "PYTHONPATH": str(root)}
    out = subprocess.run([sys.executable, "-c", VECTOR_SCRIPT], cwd=root, env=env,
                         capture_output=True, text=True, timeout=HANG_GUARD)
    assert out.returncode == 0, out.stderr
    here: dict = {}
    exec(VECTOR_SCRIPT.replace("print(h.hexdigest())", "result = h.hexdigest()"), here)
    assert out.stdout.strip() == here["result"]
