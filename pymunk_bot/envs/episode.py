"""One navigation episode after another in one simulation: what a single env and each slot of
the vector env hold. No RL library here either."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from pymunk_bot.config import ScenarioConfig, parse_scenario, scenario_data
from pymunk_bot.config.guidance import PlanGuidanceConfig
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.engine.replicas import Replicas
from pymunk_bot.engine.simulation import Simulation
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.envs.randomize import Randomization, start_pose
from pymunk_bot.envs.robot_task import RobotTask
from pymunk_bot.envs.task import RewardWeights, end_info, load_config, prepare_scenario, sample_goal

MAX_CONTROL_PERIOD = 10.0  # [s]
MAX_EPISODE_TIME = 24 * 3600.0  # [s] of simulated time
SEED_BOUND = 2**31 - 1  # simulation seeds drawn from the episode's generator lie below this


def advance(sims: Sequence[Simulation], steps: int) -> None:
    """Advance every simulation by ``steps`` physics steps: one control period for all.

    For worlds of their own (each world runs its steps in one go: interleaving them tick by
    tick measured 1.6x slower for 16 worlds, each Space falling out of the caches between its
    ticks). Copies sharing a space advance together instead: :meth:`Replicas.step`.
    """
    for sim in sims:
        for _ in range(steps):
            sim.step()


def episode_timing(config: ScenarioConfig, control_period: float,
                   max_episode_time: float | None) -> tuple[int, float, float]:
    """(physics steps per action, control period [s], time limit [s]), checked."""
    if not (math.isfinite(control_period) and 0 < control_period <= MAX_CONTROL_PERIOD):
        raise ValueError(f"control_period must be in (0, {MAX_CONTROL_PERIOD}] s "
                         f"(got {control_period})")
    steps = max(1, round(control_period / config.world.dt))
    limit = config.world.duration if max_episode_time is None else float(max_episode_time)
    if not (math.isfinite(limit) and 0 < limit <= MAX_EPISODE_TIME):
        raise ValueError(f"max_episode_time must be in (0, {MAX_EPISODE_TIME:g}] s "
                         f"(got {max_episode_time})")
    return steps, steps * config.world.dt, limit


class NavigationEpisode:
    """A scenario prepared for one learning robot, and its current episode.

    ``control_period`` [s] is rounded to whole physics steps; the robot's LiDAR scans once per
    period, just before the observation is taken.
    """

    def __init__(self, scenario: str | Path | dict | ScenarioConfig | None = None,
                 robot: str | None = None, control_period: float = 0.1,
                 max_episode_time: float | None = None,
                 lidar: Mapping[str, Any] | None = None,
                 reward: RewardWeights | Mapping[str, float] | str | None = None,
                 random_goal: bool = False, pose_source: str = "ground_truth",
                 terminate_on_collision: bool = False,
                 randomize: Mapping[str, Any] | Randomization | None = None,
                 plan_guidance: bool | Mapping[str, float] | PlanGuidanceConfig | None = None,
                 observation: str = "lidar") -> None:
        guidance = PlanGuidanceConfig.of(plan_guidance)  # ValueError naming the key
        config, self.source = load_config(scenario)
        # control period and time limit [s]
        self.steps_per_action, self.control_period, self.time_limit = episode_timing(
            config, control_period, max_episode_time)
        self.config, (self.robot_name,) = prepare_scenario(
            config, self.source, None if robot is None else [robot], lidar, self.control_period,
            need_goal=not random_goal)
        self.random_goal = bool(random_goal)
        self.terminate_on_collision = bool(terminate_on_collision)
        robot_config = next(r for r in self.config.robots if r.name == self.robot_name)
        self.task = RobotTask(robot_config, RewardWeights.from_any(reward), pose_source,
                              guidance, self.control_period, observation)
        self._map: tuple[ScenarioConfig, MapInfo] | None = None  # the last world's, planned on
        self._lidar = dict(lidar or {})
        self._base = scenario_data(config, exclude_unset=True)  # what each draw starts from
        self.randomize: Randomization | None = None
        if isinstance(randomize, Randomization):  # checked already (the vector env's copies)
            self.randomize = randomize
        elif randomize is not None:
            self.randomize = Randomization.parse(randomize, self.source)
            self.randomize.check(self._base, self.robot_name, self.source)
        if self.randomize is not None and self.randomize.maps and not self.random_goal:
            raise ScenarioError(self.source, "randomize.maps", "a map world needs a drawn goal: "
                                                               "pass random_goal=True")
        self.sim: Simulation | None = None
        self.done = True  # no episode under way until reset
        self._copy: tuple[Replicas, int] | None = None

    def share(self, replicas: "Replicas", index: int) -> None:
        """Play every episode in copy ``index`` of ``replicas`` (a space shared with other
        episodes) instead of a simulation of its own."""
        self._copy = (replicas, index)
        self.sim = None

    def reset(self, rng: np.random.Generator) -> tuple[np.ndarray, dict]:
        """Start an episode: the simulation seed (and a random goal) come from ``rng``."""
        seed = int(rng.integers(SEED_BOUND))
        if self.randomize is not None and self.randomize.changes_world:
            self.sim = self._drawn_simulation(rng, seed)
        elif self._copy is not None:
            replicas, index = self._copy
            replicas.reset(index, seed)
            self.sim = replicas.sims[index]
        elif self.sim is None:
            self.sim = Simulation(self.config, seed=seed, source=self.source)
        else:
            self.sim.reset(seed)
        robot = self.sim.robots[self.robot_name]
        if self.random_goal:
            robot.set_goal(sample_goal(self.sim, robot, rng))
        self.task.start(robot, None if self.task.guide is None else self._world_map(self.sim))
        self.done = False
        return self.task.observe(), {"sim_seed": seed, "goal": tuple(self.task.goal()),
                                     "distance_to_goal": self.task.goal_distance(),
                                     "collisions": robot.collisions}

    def _world_map(self, sim: Simulation) -> MapInfo:
        """The map plan guidance plans on: the scenario's arena and fixed obstacles (a drawn
        world's, or its map file's), made once per world."""
        if self._map is None or self._map[0] is not sim.config:
            self._map = (sim.config, MapInfo.from_scenario(sim.config))
        return self._map[1]

    def _drawn_simulation(self, rng: np.random.Generator, seed: int) -> Simulation:
        """A simulation of this episode's drawn scenario (``randomize``), its start pose drawn
        in the drawn world when ``randomize.start``."""
        assert self.randomize is not None
        data = self.randomize.scenario(self._base, self.robot_name, rng, self.source)
        sim = Simulation(self._prepared(data), seed=seed, source=self.source)
        if self.randomize.start:
            x, y, theta = start_pose(sim, sim.robots[self.robot_name], rng)
            learner = next(r for r in data["robots"] if r["name"] == self.robot_name)
            learner["pose"] = [x, y, theta]
            sim = Simulation(self._prepared(data), seed=seed, source=self.source)
        return sim

    def _prepared(self, data: dict) -> ScenarioConfig:
        """A drawn scenario made ready for the agent, as the constructor's; its observation
        must keep the size the spaces were made for."""
        config, _ = prepare_scenario(parse_scenario(data, self.source), self.source,
                                     [self.robot_name], self._lidar, self.control_period,
                                     need_goal=not self.random_goal)
        robot = next(r for r in config.robots if r.name == self.robot_name)
        if robot.lidar is None or robot.lidar.beams != self.task.beams or (
                robot.lidar.max_range != self.task.max_range):
            raise ScenarioError(self.source, "randomize", "a drawn scenario changes the "
                                "learning robot's LiDAR beams or range (the observation's size)")
        return config

    def act(self, action: np.ndarray) -> None:
        self.task.act(action)

    def finish(self, out: np.ndarray | None = None
               ) -> tuple[np.ndarray, float, bool, bool, dict]:
        """(obs, reward, terminated, truncated, info) once the physics has advanced, the
        observation written into ``out`` if given."""
        if self.sim is None:
            raise RuntimeError("call reset() before finish()")
        obs = np.empty(self.task.obs_size, dtype=np.float32) if out is None else out
        reward, terminated, info = self.task.outcome(self.control_period,
                                                     self.terminate_on_collision, obs=obs)
        time = self.sim.time
        truncated = not terminated and time >= self.time_limit - 1e-9
        info["time"] = time
        if terminated or truncated:
            info.update(end_info(self.sim, self.robot_name))
            self.done = True
        return obs, reward, terminated, truncated, info
