"""The ``crowd_state`` observation (pymunk_bot/policy/crowd_io.py): what it holds, its bounds,
the env and the ``policy`` controller building it alike, the file recording it, CrowdNav's
reward shape."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import pymunk_bot as pb
from pymunk_bot.policy.crowd_io import (
    HUMAN_FEATURES, CrowdObservationBuilder, crowd_observation_bounds, time_to_collision,
)
from pymunk_bot.policy.files import MlpPolicy, PolicyFileError, load_policy
from pymunk_bot.policy.io import ActionScale

gym = pytest.importorskip("gymnasium")

from pymunk_bot.envs import MultiRobotEnv, NavigationEnv  # noqa: E402
from pymunk_bot.envs.evaluation import run_episodes  # noqa: E402
from command import pymunk_bot  # noqa: E402

OMNI = ActionScale(1.0, 2.0, 1.0)
FIRST = 3 + 3  # goal features and an omni robot's previous action


def crowd(positions, velocities, radii):
    return SimpleNamespace(positions=np.array(positions, float).reshape(-1, 2),
                           velocities=np.array(velocities, float).reshape(-1, 2),
                           radii=np.array(radii, float))


def test_a_human_ahead_walking_at_the_robot_reads_in_the_robot_frame():
    builder = CrowdObservationBuilder(2, OMNI, 0.3)
    out = np.empty(builder.size, dtype=np.float32)
    # the robot faces +y (theta = pi/2); a human 2.6 m ahead walks at it at 1 m/s
    builder.fill(out, (0.0, 0.0, math.pi / 2), (4.0, 1.0, 0.0), np.zeros(3),
                 crowd([[0.0, 2.6]], [[0.0, -1.0]], [0.3]))
    human = out[FIRST:FIRST + HUMAN_FEATURES]
    assert human[0] == 1.0  # present
    assert human[1:3] == pytest.approx([2.6 / 3.6, 0.0], abs=1e-6)  # ahead, p / (|p| + 1 m)
    assert human[3:5] == pytest.approx([-0.5, 0.0], abs=1e-6)  # coming at it, / 2 m/s
    assert human[5] == pytest.approx(0.6 / 1.6)  # radius sum 0.6 m
    assert human[6] == pytest.approx(0.5 / (0.5 + 2.0))  # gap 2 m
    assert human[7] == pytest.approx(1 / (1 + 2.0))  # meets it in 2 s
    # the second slot: absent, all zeros
    assert not out[FIRST + HUMAN_FEATURES:].any()
    assert out[0] == pytest.approx(0.8) and out[1:3] == pytest.approx([1.0, 0.0])


def test_turning_the_whole_scene_does_not_change_the_observation():
    builder = CrowdObservationBuilder(3, OMNI, 0.3)
    rng = np.random.default_rng(0)
    people = crowd(rng.uniform(-4, 4, (3, 2)), rng.uniform(-1, 1, (3, 2)), [0.3, 0.25, 0.4])
    a, b = (np.empty(builder.size, dtype=np.float32) for _ in range(2))
    builder.fill(a, (1.0, 2.0, 0.3), (3.0, 0.6, 0.8), np.array([0.5, 0.0, -0.2]), people)
    turn = 1.1  # about the robot's position
    c, s = math.cos(turn), math.sin(turn)
    rot = np.array([[c, -s], [s, c]])
    moved = crowd((people.positions - (1.0, 2.0)) @ rot.T + (1.0, 2.0),
                  people.velocities @ rot.T, people.radii)
    builder.fill(b, (1.0, 2.0, 0.3 + turn), (3.0, 0.6, 0.8), np.array([0.5, 0.0, -0.2]), moved)
    np.testing.assert_allclose(a, b, atol=1e-6)


def test_time_to_collision():
    assert time_to_collision(np.array([3.0, 0.0]), np.array([-1.0, 0.0]), 1.0) == \
        pytest.approx(2.0)
    assert time_to_collision(np.array([3.0, 0.0]), np.array([1.0, 0.0]), 1.0) == math.inf
    assert time_to_collision(np.array([3.0, 2.0]), np.array([-1.0, 0.0]), 1.0) == math.inf
    assert time_to_collision(np.array([0.5, 0.0]), np.array([1.0, 0.0]), 1.0) == 0.0


ROBOT = {"name": "r1", "drive": "omni", "pose": [12.0, 8.0, 1.5707963267948966], "radius": 0.3,
         "max_speed": 1.0, "max_accel": 100.0, "localization": "ground_truth",
         "crowd_state": {"max_humans": 5}, "lidar": {"beams": 8, "max_range": 8.0},
         "goal": {"position": [12.0, 16.0], "tolerance": 0.3}}
SCENARIO = {"name": "crowd_obs", "world": {"size": [24.0, 24.0], "duration": 25.0},
            "robots": [ROBOT]}
CROWD_ENV = {"scenario": SCENARIO, "control_period": 0.25, "observation": "crowd_state",
             "randomize": {"crowd": "crowdnav", "world_seeds": [100_000, 200_000]}}


def crowd_mlp(seed=3, humans=5) -> MlpPolicy:
    rng = np.random.default_rng(seed)
    inputs = FIRST + HUMAN_FEATURES * humans
    return MlpPolicy([rng.normal(0, 0.5, (inputs, 8)), rng.normal(0, 0.5, (8, 3))],
                     [rng.normal(0, 0.1, 8), np.array([0.5, 0.0, 0.0])], crowd_humans=humans)


def test_env_observations_stay_in_their_bounds_and_see_the_crowd():
    env = NavigationEnv(**CROWD_ENV)
    assert env.observation_space.shape == (FIRST + 5 * HUMAN_FEATURES,)
    low, high = crowd_observation_bounds(5, True)
    np.testing.assert_array_equal(env.observation_space.low, low)
    policy = crowd_mlp()
    obs, _ = env.reset(seed=1)
    seen = 0
    for _ in range(40):
        assert env.observation_space.contains(obs)
        seen = max(seen, int(obs[FIRST::HUMAN_FEATURES].sum()))
        obs, _, terminated, truncated, _ = env.step(policy.act(obs[None])[0])
        if terminated or truncated:
            break
    assert seen == 5  # CrowdNav's five humans, every slot filled


def test_controller_drives_exactly_as_the_env_steps(tmp_path):
    policy = crowd_mlp()
    policy.save(tmp_path / "crowd.npz")
    env = NavigationEnv(**CROWD_ENV)
    obs, info = env.reset(seed=4)
    stepped = []
    for _ in range(60):
        obs, _, terminated, truncated, _ = env.step(policy.act(obs[None])[0])
        stepped.append(env.sim.robots["r1"].pose)
        if terminated or truncated:
            break
    # the episode's drawn scenario, the policy as its robot's controller
    config = env.sim.config.model_dump(mode="json", exclude_unset=True)
    config["robots"][0]["controller"] = {"type": "policy", "path": str(tmp_path / "crowd.npz"),
                                         "rate": 4.0}
    sim = pb.Simulation.from_dict(config, seed=info["sim_seed"])
    driven = []
    for _ in stepped:
        for _ in range(env.episode.steps_per_action):
            sim.step()
        driven.append(sim.robots["r1"].pose)
    assert len(stepped) > 10
    np.testing.assert_array_equal(np.array(driven), np.array(stepped))  # bit for bit


def test_the_npz_records_the_observation_and_a_mismatch_is_refused(tmp_path):
    crowd_mlp().save(tmp_path / "crowd.npz")
    loaded = load_policy(tmp_path / "crowd.npz")
    assert loaded.crowd_humans == 5
    with pytest.raises(PolicyFileError, match="crowd_state observation"):
        run_episodes(loaded, {**CROWD_ENV, "observation": "lidar"}, [0])
    lidar_policy = MlpPolicy([np.zeros((8 + 9, 3))], [np.zeros(3)])
    with pytest.raises(PolicyFileError, match="LiDAR observation"):
        run_episodes(lidar_policy, CROWD_ENV, [0])


@pytest.mark.parametrize("keys, words", [
    ({"observation": "lidar"}, "was trained on the crowd_state observation"),
    ({}, "add 'crowd_state: {}' to the robot"),
])
def test_a_scenario_that_cannot_run_a_crowd_policy_is_one_line_exit_2(tmp_path, keys, words):
    crowd_mlp().save(tmp_path / "crowd.npz")
    robot = {k: v for k, v in ROBOT.items() if keys or k != "crowd_state"}
    robot["controller"] = {"type": "policy", "path": "crowd.npz", **keys}
    data = {**SCENARIO, "robots": [robot]}
    import yaml
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    result = pymunk_bot("validate", str(tmp_path / "s.yaml"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert words in result.stderr and "robots[0].controller" in result.stderr


def test_the_env_refuses_the_crowd_observation_without_the_sensor():
    robot = {k: v for k, v in ROBOT.items() if k != "crowd_state"}
    with pytest.raises(ValueError, match="crowd_state: {}"):
        NavigationEnv({**SCENARIO, "robots": [robot]}, observation="crowd_state")
    with pytest.raises(ValueError, match="observation must be one of"):
        NavigationEnv(SCENARIO, observation="radar")


def test_multi_robot_env_builds_the_same_observation():
    two = {"name": "two", "world": {"size": [10.0, 6.0], "duration": 5.0},
           "obstacles": [{"type": "pedestrian", "center": [5.0, 3.0], "goals": [[5.0, 5.0]]}],
           "robots": [{**ROBOT, "pose": [1.0, 1.0, 0.0], "goal": {"position": [8.0, 1.0]}},
                      {**ROBOT, "name": "r2", "pose": [1.0, 5.0, 0.0],
                       "goal": {"position": [8.0, 5.0]}}]}
    env = MultiRobotEnv(two, observation="crowd_state")
    observations, _ = env.reset(seed=0)
    for name, obs in observations.items():
        assert obs.shape == (FIRST + 5 * HUMAN_FEATURES,)
        assert obs[FIRST] == 1.0 and not obs[FIRST + HUMAN_FEATURES:].any()  # one human


def test_crowdnav_reward_is_crowdnavs():
    """+1 on arrival, -0.25 at a collision, (d - 0.2) * 0.5 * dt within 0.2 m of a human."""
    scene = {"name": "reward", "world": {"size": [10.0, 6.0], "duration": 20.0},
             "obstacles": [{"type": "pedestrian", "center": [5.0, 3.0], "goals": [[5.0, 3.0]],
                            "radius": 0.3, "policy": "orca", "react_to_robot": False}],
             "robots": [{**ROBOT, "pose": [3.0, 3.0, 0.0], "goal": {"position": [8.0, 3.0]}}]}
    env = NavigationEnv(scene, control_period=0.25, observation="crowd_state",
                        reward="crowdnav", terminate_on_collision=True)
    env.reset(seed=0)
    rewards, gaps = [], []
    for _ in range(20):
        _, reward, terminated, _, info = env.step(np.array([0.5, 0.0, 0.0]))
        rewards.append(reward)
        gaps.append(info["clearance"])
        if terminated:
            break
    assert info["new_collisions"] >= 1  # walked into the standing human
    assert terminated and not info["is_success"]
    for reward, gap in zip(rewards[:-1], gaps[:-1]):
        expected = (gap - 0.2) * 0.5 * 0.25 if gap < 0.2 else 0.0
        assert reward == pytest.approx(expected, abs=1e-12)
    assert any(0 < g < 0.2 for g in gaps[:-1])  # a discomfort step was checked
    # the collision: -0.25 per contact episode begun in the step (a push can begin several)
    crowding = min(1.0, max(0.0, 1.0 - gaps[-1] / 0.2))
    assert rewards[-1] == pytest.approx(-0.25 * info["new_collisions"] - 0.1 * 0.25 * crowding)
    with pytest.raises(ValueError, match="preset"):
        NavigationEnv(scene, reward="crowdnv")


def test_crowd_layouts_come_from_world_seeds():
    """A trainer keeps clear of the test cases (seeds 0 to 499): randomize.world_seeds bounds
    the layout seeds a crowd suite is drawn with."""
    from pymunk_bot.benchmark.suite import episode_data

    env = NavigationEnv(**{**CROWD_ENV, "randomize": {"crowd": "crowdnav",
                                                      "world_seeds": [7, 8]}})
    expected = [o["center"] for o in episode_data(load_suite_entry(), 7)["obstacles"]
                if o.get("type") == "pedestrian"]
    for seed in (0, 1):
        env.reset(seed=seed)
        starts = [list(o.center) for o in env.sim.config.obstacles
                  if getattr(o, "type", None) == "pedestrian"]
        np.testing.assert_allclose(starts, expected)


def load_suite_entry():
    from pymunk_bot.benchmark.suite import load_suite

    return load_suite("crowdnav")[0]
