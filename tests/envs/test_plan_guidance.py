"""Plan guidance in the envs: the goal a policy sees lies along an A* path on the map (toward a
door, around an obstacle seen on the way), in the single, vector and multi-robot envs alike."""
from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from pymunk_bot.envs import NavigationEnv  # noqa: E402
from pymunk_bot.envs.vector import NavigationVectorEnv  # noqa: E402
from pymunk_bot.policy.io import GOAL_COS, GOAL_DISTANCE, GOAL_SIN  # noqa: E402

BEAMS = 16
DOOR = (4.0, 5.25)  # [m] the gap above the wall between the two rooms


def office(pose=(2.0, 1.0, 0.0), goal=(6.0, 1.0), max_range=5.0, obstacles=()) -> dict:
    """Two rooms split by a wall at x = 4 m, open above y = 4.5 m (the door)."""
    return {"name": "two_rooms", "world": {"size": [8.0, 6.0], "duration": 30.0},
            "obstacles": [{"type": "wall", "start": [4.0, 0.0], "end": [4.0, 4.5],
                           "thickness": 0.1}, *obstacles],
            "robots": [{"name": "r1", "pose": list(pose),
                        "lidar": {"beams": BEAMS, "max_range": max_range},
                        "goal": {"position": list(goal), "tolerance": 0.2}}]}


def goal_direction(obs: np.ndarray, theta: float) -> np.ndarray:
    """The unit vector [world frame] of the goal bearing an observation shows."""
    bearing = math.atan2(obs[BEAMS + GOAL_SIN], obs[BEAMS + GOAL_COS]) + theta
    return np.array([math.cos(bearing), math.sin(bearing)])


def test_goal_behind_a_wall_is_seen_toward_the_door():
    plain = NavigationEnv(office())
    guided = NavigationEnv(office(), plan_guidance=True)
    assert guided.observation_space == plain.observation_space  # the same layout
    obs_plain, _ = plain.reset(seed=0)
    obs_guided, _ = guided.reset(seed=0)
    # Without guidance: straight at the goal, through the wall.
    np.testing.assert_allclose(goal_direction(obs_plain, 0.0), [1.0, 0.0], atol=1e-6)
    # With it: toward the door (up and a little right), not at the goal.
    to_door = np.subtract(DOOR, (2.0, 1.0))
    to_door /= np.linalg.norm(to_door)
    assert goal_direction(obs_guided, 0.0) @ to_door > 0.95
    # Its distance is along the path (over 8 m), not the 4 m straight line.
    squashed = float(obs_guided[BEAMS + GOAL_DISTANCE])
    assert squashed / (1.0 - squashed) > 8.0
    np.testing.assert_array_equal(obs_guided[:BEAMS], obs_plain[:BEAMS])  # the scan unchanged


def test_guided_features_become_the_goals_near_it():
    env = NavigationEnv(office(pose=(5.0, 1.0, 0.5), goal=(6.0, 1.2)), plan_guidance=True)
    plain = NavigationEnv(office(pose=(5.0, 1.0, 0.5), goal=(6.0, 1.2)))
    np.testing.assert_array_equal(env.reset(seed=1)[0], plain.reset(seed=1)[0])


def test_a_new_obstacle_on_the_path_makes_it_replan_around_it():
    # A crate (movable: not on the map) straight between the robot and its goal, beyond the
    # LiDAR's 2 m at the start: the path goes straight until the robot sees the crate.
    crate = {"type": "box", "center": [4.0, 2.0], "size": [1.0, 1.2], "movable": True,
             "mass": 50.0}
    beams = 64
    data = {"name": "crate_on_the_way", "world": {"size": [8.0, 4.0], "duration": 30.0},
            "obstacles": [crate],
            "robots": [{"name": "r1", "pose": [0.8, 2.0, 0.0],
                        "lidar": {"beams": beams, "max_range": 2.0},
                        "goal": {"position": [7.2, 2.0], "tolerance": 0.2}}]}
    env = NavigationEnv(data, plan_guidance={"replan_period": 0.5})
    obs, _ = env.reset(seed=0)
    guide = env.episode.task.guide
    assert abs(obs[beams + GOAL_SIN]) < 1e-6 and guide.plans == 1  # straight through the crate
    turned = None
    for _ in range(40):
        obs, _, terminated, _, _ = env.step([0.6, 0.0])  # straight on, whatever it sees
        assert not terminated
        if guide.plans > 1:
            turned = obs
            break
    assert turned is not None, "the crate in view never made it replan"
    assert env.sim.robots["r1"].pose[0] < 3.0  # well before the crate
    assert abs(turned[beams + GOAL_SIN]) > 0.2  # it now steers off the straight line
    # The new path passes the crate's face (seen: x = 3.5 m, y in [1.4, 2.6]) with room for
    # the robot; the crate's far side is not seen yet.
    path = np.asarray(guide.path)
    samples = np.concatenate([np.linspace(a, b, 200) for a, b in zip(path, path[1:])])
    at_face = samples[np.abs(samples[:, 0] - 3.5) < 0.02]
    assert len(at_face) and (np.abs(at_face[:, 1] - 2.0) > 0.6 + 0.9 * env.episode.task.radius
                             ).all()


def test_unreachable_goal_falls_back_to_the_final_goal():
    closed = office()
    closed["obstacles"][0]["end"] = [4.0, 6.0]  # no door
    plain, guided = NavigationEnv(closed), NavigationEnv(closed, plan_guidance=True)
    np.testing.assert_array_equal(guided.reset(seed=0)[0], plain.reset(seed=0)[0])
    assert guided.episode.task.guide.path is None


def test_vector_env_shows_what_single_envs_show():
    kwargs = {"scenario": office(), "plan_guidance": True, "random_goal": True}
    vector = NavigationVectorEnv(num_envs=3, **kwargs)
    singles = [NavigationEnv(**kwargs) for _ in range(3)]
    obs, _ = vector.reset(seed=5)
    expected = [env.reset(seed=5 + i)[0] for i, env in enumerate(singles)]
    rng = np.random.default_rng(0)
    for _ in range(25):
        np.testing.assert_array_equal(obs, np.array(expected))
        actions = rng.uniform(-1, 1, (3, 2)).astype(np.float32)
        obs, *_ = vector.step(actions)
        expected = [env.step(a)[0] for env, a in zip(singles, actions)]
        assert not any(env.episode.done for env in singles)


def test_multi_robot_env_guides_every_agent():
    pytest.importorskip("pettingzoo")
    from pymunk_bot.envs import MultiRobotEnv

    data = office()
    data["robots"].append({"name": "r2", "pose": [6.0, 1.0, math.pi],
                           "lidar": {"beams": BEAMS, "max_range": 5.0},
                           "goal": {"position": [2.0, 1.0], "tolerance": 0.2}})
    env = MultiRobotEnv(data, plan_guidance=True)
    observations, _ = env.reset(seed=0)
    up = goal_direction(observations["r1"], 0.0)
    assert up[1] > 0.8  # r1 heads for the door, not through the wall
    assert goal_direction(observations["r2"], math.pi)[1] > 0.8  # so does r2


@pytest.mark.parametrize("value, words", [
    ({"lookahead": -1.0}, "plan_guidance.lookahead"),
    ({"lookahed": 1.0}, "plan_guidance.lookahed"),
    ("yes", "plan_guidance must be true, false or a mapping"),
])
def test_bad_settings_name_the_key(value, words):
    with pytest.raises(ValueError, match=words) as caught:
        NavigationEnv(office(), plan_guidance=value)
    assert "\n" not in str(caught.value)


def test_a_planning_grid_too_large_is_refused_naming_the_key():
    big = office()
    big["world"]["size"] = [400.0, 400.0]  # 400 million cells at 2 cm
    env = NavigationEnv(big, plan_guidance={"resolution": 0.02})
    with pytest.raises(ValueError, match=r"plan_guidance.resolution: .*\(at most 4000000\)"):
        env.reset(seed=0)


PROGRESS_ONLY = {"contact": 0.0, "clearance": 0.0, "time": 0.0, "success": 0.0}


def test_guided_reward_pays_progress_toward_the_door_not_the_straight_line():
    # The goal is straight ahead behind the wall; the door is up. Driving up toward the door
    # takes the robot no nearer in a straight line, but nearer along the path: with guidance
    # the progress term pays for it.
    data = office(pose=(2.0, 1.0, math.pi / 2))
    guided = NavigationEnv(data, plan_guidance=True, reward=PROGRESS_ONLY)
    plain = NavigationEnv(data, reward=PROGRESS_ONLY)
    obs, _ = guided.reset(seed=0)
    plain.reset(seed=0)

    def along(o: np.ndarray) -> float:  # [m] the guided distance the observation shows
        squashed = float(o[BEAMS + GOAL_DISTANCE])
        return squashed / (1.0 - squashed)

    start = along(obs)
    guided_total = plain_total = 0.0
    for _ in range(20):  # 2 s up at 0.5 of full speed
        obs, reward, *_ = guided.step([0.5, 0.0])
        guided_total += reward
        plain_total += plain.step([0.5, 0.0])[1]
    assert plain_total < 0.0  # farther from the goal in a straight line
    assert guided_total > 0.3  # but nearer along the path to it: paid
    assert guided_total == pytest.approx(start - along(obs), abs=1e-4)  # float32 obs


def test_multi_robot_env_pays_guided_progress_as_the_single_env():
    from pymunk_bot.envs import MultiRobotEnv

    data = office(pose=(2.0, 1.0, math.pi / 2))
    single = NavigationEnv(data, plan_guidance=True, reward=PROGRESS_ONLY)
    multi = MultiRobotEnv(data, plan_guidance=True, reward=PROGRESS_ONLY)
    single.reset(seed=0)
    multi.reset(seed=0)
    single_total = multi_total = 0.0
    for _ in range(20):  # up toward the door, as above
        obs, reward, *_ = single.step([0.5, 0.0])
        observations, rewards, *_ = multi.step({"r1": np.array([0.5, 0.0], np.float32)})
        np.testing.assert_array_equal(observations["r1"], obs)
        single_total += reward
        multi_total += rewards["r1"]
    assert multi_total > 0.3
    assert multi_total == pytest.approx(single_total, abs=1e-6)  # its world is built apart
