"""A native vector env: N navigation worlds stepped together through one call.

    envs = gym.make_vec("pymunk_bot/Navigation-v0", num_envs=16,
                        vectorization_mode="vector_entry_point")

Sub-env i reset with seed s + i plays exactly the episode a single env reset with that seed
plays. Autoreset follows Gymnasium 1.x (NEXT_STEP by default: the step after an episode ends
resets that slot, ignores its action and returns reward 0; SAME_STEP and DISABLED also work).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .episode import NavigationEpisode, advance
from .navigation import make_spaces

if TYPE_CHECKING:
    from ..sim import Simulation
    from .render import FrameRenderer

MAX_ENVS = 4096


class NavigationVectorEnv(VectorEnv):
    """``num_envs`` copies of :class:`~pymunk_bot.envs.NavigationEnv` (same keyword
    arguments) whose simulations advance in lockstep (:func:`~pymunk_bot.envs.episode.advance`)."""

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int = 1, render_mode: str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 **kwargs: Any) -> None:
        if not (isinstance(num_envs, int) and 1 <= num_envs <= MAX_ENVS):
            raise ValueError(f"num_envs must be an integer in [1, {MAX_ENVS}] (got {num_envs!r})")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"the vector env renders only 'rgb_array' (got {render_mode!r})")
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        first = NavigationEpisode(**kwargs)
        # The others share the prepared (validated) scenario: no parsing per copy.
        kwargs = {**kwargs, "scenario": first.config}
        self.episodes = [first] + [NavigationEpisode(**kwargs) for _ in range(num_envs - 1)]
        for episode in self.episodes[1:]:
            episode.source = first.source
        self.num_envs = num_envs
        self.render_mode = render_mode
        self.single_observation_space, self.single_action_space = make_spaces(first.task)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._rngs = [seeding.np_random(None)[0] for _ in range(num_envs)]
        self._obs = np.zeros((num_envs, first.task.obs_size), dtype=np.float32)
        self._autoreset = np.zeros(num_envs, dtype=np.bool_)
        self._renderers: list[FrameRenderer] | None = None

    # One generator per sub-env, as gymnasium's own SyncVectorEnv returns; VectorEnv declares one.
    @property  # type: ignore[misc]
    def np_random(self) -> tuple[np.random.Generator, ...]:  # type: ignore[override]
        return tuple(self._rngs)

    def reset(self, *, seed: int | list[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        n = self.num_envs
        seeds = [seed + i for i in range(n)] if isinstance(seed, int) else seed
        if seeds is not None and len(seeds) != n:
            raise ValueError(f"a list of seeds needs one per env ({n}), got {len(seeds)}")
        mask = np.ones(n, dtype=np.bool_)
        if options and "reset_mask" in options:
            mask = np.asarray(options["reset_mask"], dtype=np.bool_)
            if mask.shape != (n,) or not mask.any():
                raise ValueError(f"options['reset_mask'] must be {n} booleans, some True")
        infos: dict = {}
        for i in map(int, np.flatnonzero(mask)):
            env_seed = None if seeds is None else seeds[i]
            if env_seed is not None:
                self._rngs[i] = seeding.np_random(int(env_seed))[0]
            self._obs[i], info = self.episodes[i].reset(self._rngs[i])
            infos = self._add_info(infos, info, i)
        self._autoreset[mask] = False
        self._attach_renderers()
        return self._obs.copy(), infos

    def step(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        n = self.num_envs
        actions = np.asarray(actions, dtype=np.float32).reshape(n, -1)
        sims: list[Simulation] = []
        for episode in self.episodes:
            if episode.sim is None:
                raise gym.error.ResetNeeded("call reset() before step()")
            sims.append(episode.sim)
        rewards = np.zeros(n, dtype=np.float64)
        terminated = np.zeros(n, dtype=np.bool_)
        truncated = np.zeros(n, dtype=np.bool_)
        stepping = [i for i in range(n) if not self._autoreset[i]]
        for i in stepping:
            self.episodes[i].act(actions[i])
        advance([sims[i] for i in stepping],
                self.episodes[0].steps_per_action)
        infos: dict = {}
        for i in range(n):
            episode = self.episodes[i]
            if self._autoreset[i]:  # NEXT_STEP: this step is the reset
                self._obs[i], info = episode.reset(self._rngs[i])
            else:
                (self._obs[i], rewards[i], terminated[i], truncated[i],
                 info) = episode.finish(self._obs[i])
                if self.autoreset_mode == AutoresetMode.SAME_STEP and (terminated[i] or
                                                                       truncated[i]):
                    infos = self._add_info(infos, {"final_obs": self._obs[i].copy(),
                                                   "final_info": info}, i)
                    self._obs[i], info = episode.reset(self._rngs[i])
            infos = self._add_info(infos, info, i)
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            self._autoreset = terminated | truncated
        elif self.autoreset_mode == AutoresetMode.DISABLED:
            self._autoreset[:] = False
            for k in np.flatnonzero(terminated | truncated):
                self.episodes[k].done = True
        self._attach_renderers()
        return self._obs.copy(), rewards, terminated, truncated, infos

    def render(self) -> tuple[np.ndarray, ...] | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode='rgb_array'")
            return None
        if self._renderers is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        return tuple(r.rgb() for r in self._renderers)

    def _attach_renderers(self) -> None:
        if self.render_mode is not None and self._renderers is None:
            from .render import FrameRenderer

            self._renderers = [FrameRenderer(e.sim) for e in self.episodes]

    def close_extras(self, **kwargs: Any) -> None:
        for renderer in self._renderers or []:
            renderer.close()
        self._renderers = None
