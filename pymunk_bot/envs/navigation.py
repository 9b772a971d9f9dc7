"""`pymunk_bot/Navigation-v0`: drive one robot of a scenario to its goal (see docs/learning.md)."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from pymunk_bot.config import ScenarioConfig
from pymunk_bot.envs.episode import NavigationEpisode, advance
from pymunk_bot.envs.task import RewardWeights

if TYPE_CHECKING:
    from pymunk_bot.engine.simulation import Simulation
    from pymunk_bot.envs.render import FrameRenderer

RENDER_MODES = ("human", "rgb_array")


def make_spaces(task) -> tuple[spaces.Box, spaces.Box]:
    """(observation space, action space) of a RobotTask."""
    low, high = task.obs_bounds()
    observation = spaces.Box(low, high, dtype=np.float32)
    action = spaces.Box(-1.0, 1.0, shape=(task.action_size,), dtype=np.float32)
    return observation, action


class NavigationEnv(gym.Env):
    """Reach the goal of one robot in a scenario, through real contacts and a simulated LiDAR.

    Args:
        scenario: a path, a shipped scenario's name, a scenario dict or config; None = the
            built-in default scenario.
        render_mode: None, "rgb_array" (HxWx3 uint8 frames) or "human" (a window).
        robot: which robot learns (default: the first); the others keep their controllers.
        control_period: seconds per action [s], rounded to whole physics steps (0.1 s = 6 steps
            of 1/60 s); the robot's LiDAR scans once per period.
        max_episode_time: simulated seconds before truncation (default: the scenario's
            ``world.duration``).
        lidar: overrides of the robot's LiDAR keys, e.g. ``{"beams": 180}``.
        reward: weights (see :class:`~pymunk_bot.envs.task.RewardWeights`).
        random_goal: draw a free goal position each episode instead of the scenario's.
        pose_source: "ground_truth" (default) or "odometry": the pose the goal is seen from.
        terminate_on_collision: end the episode at the first contact.
        randomize: what to draw anew every episode: a generated world, a start pose, scenario
            keys (see :mod:`pymunk_bot.envs.randomize`).
        plan_guidance: True, or a mapping of ``lookahead`` [m], ``replan_period`` [s],
            ``off_path`` [m], ``resolution`` [m]: the observation's goal features point along
            an A* path on the scenario's map instead of at the goal (same observation size;
            :mod:`pymunk_bot.planning.guidance`, docs/learning.md). None or False: off.
        observation: "lidar" (the default: :mod:`pymunk_bot.policy.io`) or "crowd_state": the
            nearest humans' true states in the robot frame (:mod:`pymunk_bot.policy.crowd_io`;
            the robot needs ``crowd_state: {...}``).

    ``info["is_success"]`` is true when the robot reached its goal without any contact on
    the way; ``info["contact_time"]`` counts the episode's seconds in contact.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}

    def __init__(self, scenario: str | Path | dict | ScenarioConfig | None = None,
                 render_mode: str | None = None, robot: str | None = None,
                 control_period: float = 0.1, max_episode_time: float | None = None,
                 lidar: Mapping[str, Any] | None = None,
                 reward: RewardWeights | Mapping[str, float] | str | None = None,
                 random_goal: bool = False, pose_source: str = "ground_truth",
                 terminate_on_collision: bool = False,
                 randomize: Mapping[str, Any] | None = None,
                 plan_guidance: bool | Mapping[str, float] | None = None,
                 observation: str = "lidar") -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be one of {RENDER_MODES} or None "
                             f"(got {render_mode!r})")
        self.episode = NavigationEpisode(scenario, robot, control_period, max_episode_time,
                                         lidar, reward, random_goal, pose_source,
                                         terminate_on_collision, randomize, plan_guidance,
                                         observation)
        self.observation_space, self.action_space = make_spaces(self.episode.task)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": 1.0 / self.episode.control_period}
        self._renderer: FrameRenderer | None = None

    @property
    def sim(self) -> Simulation | None:
        """The running :class:`~pymunk_bot.Simulation` (None before the first reset)."""
        return self.episode.sim

    def reset(self, *, seed: int | None = None, options: dict | None = None
              ) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        obs, info = self.episode.reset(self.np_random)
        if self.render_mode == "human":
            self._render_frame()
        return obs, info

    def step(self, action) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self.episode.sim is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        self.episode.act(action)
        advance([self.episode.sim], self.episode.steps_per_action)
        result = self.episode.finish()
        if self.render_mode == "human":
            self._render_frame()
        return result

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode="
                            "'rgb_array' or 'human' to gym.make")
            return None
        return self._render_frame()

    def _render_frame(self) -> np.ndarray | None:
        if self.episode.sim is None:
            self.episode.reset(self.np_random)  # a frame before the first reset
        if self._renderer is not None and self._renderer.sim is not self.episode.sim:
            self._renderer.close()  # a world drawn for this episode (randomize): a new view
            self._renderer = None
        if self._renderer is None:
            from pymunk_bot.envs.render import FrameRenderer

            self._renderer = FrameRenderer(self.episode.sim, agents=[self.episode.robot_name])
        if self.render_mode == "rgb_array":
            return self._renderer.rgb()
        from pymunk_bot.viewer import ViewerUnavailable

        try:
            self._renderer.show(f"pymunk-bot: {self.episode.config.name}")
        except ViewerUnavailable as exc:
            raise gym.error.Error(f"render_mode='human' needs a display ({exc}); use "
                                  "render_mode='rgb_array' when headless") from None
        return None

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
