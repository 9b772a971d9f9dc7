"""`MultiRobotEnv`: a PettingZoo ParallelEnv with one agent per robot of a scenario.

Every agent sees, acts and is rewarded as in Navigation-v0 (see :mod:`.task`). An agent whose
robot reaches its goal (or, with ``terminate_on_collision``, touches something) leaves
``agents`` and its robot holds still where it is: the others must still drive around it.
All agents are truncated together at the time limit.
"""
from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

try:
    from pettingzoo import ParallelEnv
except ImportError:  # pragma: no cover - depends on the install
    raise ImportError("MultiRobotEnv needs pettingzoo: pip install 'pymunk-bot[rl]'") from None
from gymnasium.utils import seeding

from pymunk_bot.config import ScenarioConfig
from pymunk_bot.config.guidance import PlanGuidanceConfig
from pymunk_bot.engine.simulation import Simulation
from pymunk_bot.envs.episode import SEED_BOUND, advance, episode_timing
from pymunk_bot.envs.navigation import RENDER_MODES, make_spaces
from pymunk_bot.envs.robot_task import RobotTask
from pymunk_bot.envs.task import RewardWeights, end_info, load_config, prepare_scenario
from pymunk_bot.planning.map import MapInfo

if TYPE_CHECKING:
    from pymunk_bot.envs.render import FrameRenderer

# With no scenario: four robots swapping places across a room, their routes crossing in the
# middle (the built-in default scenario has one robot, not a multi-robot task).
DEFAULT_SCENARIO = "crossing"


class MultiRobotEnv(ParallelEnv):
    """Every robot of ``scenario`` is an agent (named as the robot) driving to its own goal.

    Keyword arguments as :class:`~pymunk_bot.envs.NavigationEnv` (``lidar`` overrides apply
    to every robot, ``plan_guidance`` to every agent), except that there is no ``robot`` and
    no ``random_goal`` nor ``randomize`` (``observation="crowd_state"``: every robot needs the
    ``crowd_state`` sensor); with no ``scenario``, the shipped ``crossing`` (four
    robots, DEFAULT_SCENARIO). With plan guidance each agent plans on the scenario's map; the
    other robots are not on it (its LiDAR sees them).
    """

    metadata = {"name": "pymunk_bot_multi_robot_v0", "render_modes": list(RENDER_MODES),
                "render_fps": 10, "is_parallelizable": True}

    def __init__(self, scenario: str | Path | dict | ScenarioConfig | None = None,
                 render_mode: str | None = None, control_period: float = 0.1,
                 max_episode_time: float | None = None,
                 lidar: Mapping[str, Any] | None = None,
                 reward: RewardWeights | Mapping[str, float] | str | None = None,
                 pose_source: str = "ground_truth",
                 terminate_on_collision: bool = False,
                 plan_guidance: bool | Mapping[str, float] | None = None,
                 observation: str = "lidar") -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be one of {RENDER_MODES} or None "
                             f"(got {render_mode!r})")
        guidance = PlanGuidanceConfig.of(plan_guidance)  # ValueError naming the key
        config, self.source = load_config(DEFAULT_SCENARIO if scenario is None else scenario)
        # control period and time limit [s]
        self.steps_per_action, self.control_period, self.time_limit = episode_timing(
            config, control_period, max_episode_time)
        names = [r.name for r in config.robots]
        self.config, _ = prepare_scenario(config, self.source, names, lidar, self.control_period)
        weights = RewardWeights.from_any(reward)
        self.tasks = {r.name: RobotTask(r, weights, pose_source, guidance, self.control_period,
                                     observation) for r in self.config.robots}
        self.world_map = MapInfo.from_scenario(self.config) if guidance is not None else None
        self.terminate_on_collision = bool(terminate_on_collision)
        self.possible_agents = names
        self.agents: list[str] = []
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": 1.0 / self.control_period}
        self.sim: Simulation | None = None
        self._rng = seeding.np_random(None)[0]
        self._renderer: FrameRenderer | None = None

    @functools.lru_cache(maxsize=None)
    def observation_space(self, agent: str):
        return make_spaces(self.tasks[agent])[0]

    @functools.lru_cache(maxsize=None)
    def action_space(self, agent: str):
        return make_spaces(self.tasks[agent])[1]

    def reset(self, seed: int | None = None, options: dict | None = None
              ) -> tuple[dict[str, np.ndarray], dict[str, dict]]:
        if seed is not None:
            self._rng = seeding.np_random(int(seed))[0]
        sim_seed = int(self._rng.integers(SEED_BOUND))
        if self.sim is None:
            self.sim = Simulation(self.config, seed=sim_seed, source=self.source)
        else:
            self.sim.reset(sim_seed)
        self.agents = list(self.possible_agents)
        for name in self.agents:
            self.tasks[name].start(self.sim.robots[name], self.world_map)
        observations = {a: self.tasks[a].observe() for a in self.agents}
        infos = {a: {"sim_seed": sim_seed, "goal": tuple(self.tasks[a].goal())}
                 for a in self.agents}
        if self.render_mode == "human":
            self.render()
        return observations, infos

    def step(self, actions: dict[str, np.ndarray]):
        if self.sim is None:
            raise RuntimeError("call reset() before step()")
        live = list(self.agents)
        for name in live:
            if name not in actions:
                raise ValueError(f"no action for live agent '{name}'")
            self.tasks[name].act(actions[name])
        advance([self.sim], self.steps_per_action)
        time_up = self.sim.time >= self.time_limit - 1e-9
        observations, rewards, terminations, truncations, infos = {}, {}, {}, {}, {}
        for name in live:
            task = self.tasks[name]
            observations[name] = np.empty(task.obs_size, dtype=np.float32)
            rewards[name], terminations[name], infos[name] = task.outcome(  # fills the obs
                self.control_period, self.terminate_on_collision, obs=observations[name])
            truncations[name] = time_up and not terminations[name]
            infos[name]["time"] = self.sim.time
            if terminations[name] or truncations[name]:
                infos[name].update(end_info(self.sim, name))
                task.stop()
        self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        if self.render_mode == "human":
            self.render()
        return observations, rewards, terminations, truncations, infos

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            return None
        if self.sim is None:
            self.reset()
        if self._renderer is None:
            from pymunk_bot.envs.render import FrameRenderer

            self._renderer = FrameRenderer(self._sim(), agents=self.possible_agents)
        if self.render_mode == "rgb_array":
            return self._renderer.rgb()
        self._renderer.show(f"pymunk-bot: {self.config.name}")
        return None

    def state(self) -> np.ndarray:
        """Ground-truth poses of every robot, (n_robots * 3,) float32."""
        sim = self._sim()
        return np.concatenate([sim.robots[a].pose for a in self.possible_agents]
                              ).astype(np.float32)

    def _sim(self) -> Simulation:
        if self.sim is None:
            raise RuntimeError("call reset() first: there is no simulation yet")
        return self.sim

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
