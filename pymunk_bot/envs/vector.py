"""A native vector env: N navigation worlds stepped together, up to 16 to a pymunk Space.

    envs = gym.make_vec("pymunk_bot/Navigation-v0", num_envs=16,
                        vectorization_mode="vector_entry_point")

Sub-env i reset with seed s + i plays the episode a single env reset with that seed plays:
exactly, as long as no two moving bodies of its world touch (see docs/learning.md). Autoreset follows
Gymnasium 1.x (NEXT_STEP by default: the step after an episode ends resets that slot, ignores
its action and returns reward 0; SAME_STEP and DISABLED also work). With DISABLED, a slot whose
episode has ended is not stepped until it is reset (``options={"reset_mask": ...}``): its
robot holds still, its observation stays the final one and its reward is 0.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pymunk_bot.physics.settings import MAX_REPLICAS
from pymunk_bot.engine.replicas import NotShareable, Replicas
from pymunk_bot.envs.episode import NavigationEpisode, advance
from pymunk_bot.envs.navigation import make_spaces
from pymunk_bot.envs.robot_task import outcomes
from pymunk_bot.envs.task import end_info

if TYPE_CHECKING:
    from pymunk_bot.engine.simulation import Simulation
    from pymunk_bot.envs.render import FrameRenderer

MAX_ENVS = 4096


class NavigationVectorEnv(VectorEnv):
    """``num_envs`` copies of :class:`~pymunk_bot.envs.NavigationEnv` (same keyword
    arguments) whose simulations advance in lockstep.

    ``share_space`` (default): up to MAX_REPLICAS worlds share one pymunk Space and advance
    as one (:class:`~pymunk_bot.engine.replicas.Replicas`), pedestrians included.
    False: each world in a space of its own (slower; a pushed crate then moves exactly as in a
    single env, where sharing can change the last bits of contacts between moving bodies:
    see docs/learning.md)."""

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int = 1, render_mode: str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 share_space: bool = True, **kwargs: Any) -> None:
        if not (isinstance(num_envs, int) and 1 <= num_envs <= MAX_ENVS):
            raise ValueError(f"num_envs must be an integer in [1, {MAX_ENVS}] (got {num_envs!r})")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"the vector env renders only 'rgb_array' (got {render_mode!r})")
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        first = NavigationEpisode(**kwargs)
        # The others share the prepared (validated) scenario and the checked randomization.
        kwargs = {**kwargs, "scenario": first.config, "randomize": first.randomize}
        self.episodes = [first] + [NavigationEpisode(**kwargs) for _ in range(num_envs - 1)]
        for episode in self.episodes[1:]:
            episode.source = first.source
        self._slots: list[list[int]] = []
        drawn = first.randomize is not None and first.randomize.changes_world
        # A world drawn per episode cannot share a space with the others' worlds.
        self._shards = self._share_spaces(first) if share_space and num_envs > 1 \
            and not drawn else []
        # Step results read in one call per shared space where the task allows it.
        self._together = bool(self._shards) and all(s.stacked for s in self._shards) \
            and first.task.pose_source == "ground_truth" and not first.task.holonomic \
            and self.autoreset_mode != AutoresetMode.SAME_STEP
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
        stepping = [i for i in range(n) if not (self._autoreset[i] or self.episodes[i].done)]
        for i in range(n):  # DISABLED: an ended episode waits for its reset, holding still
            if self.episodes[i].done and not self._autoreset[i]:
                self.episodes[i].task.stop()
        shared = self._stepping_copies(stepping)
        checked = actions.astype(np.float64)
        if checked.shape[1] == self.episodes[0].task.action_size and np.isfinite(checked).all():
            clipped = np.clip(checked, -1.0, 1.0)  # what each act() would clip to
            self._command(clipped, stepping, shared)
        else:  # the env that got a bad action says what is wrong with it
            for i in stepping:
                self.episodes[i].act(actions[i])
        steps = self.episodes[0].steps_per_action
        if self._shards:  # every copy advances, even one about to be reset: it shares the step
            for shard in self._shards:
                for _ in range(steps):
                    shard.step()
        else:
            advance([sims[i] for i in stepping], steps)
        if self._together:
            infos = self._finish_together(stepping, shared, rewards, terminated, truncated)
            for i in np.flatnonzero(self._autoreset).tolist():  # NEXT_STEP: this step resets
                self._obs[i], info = self.episodes[i].reset(self._rngs[i])
                infos = self._add_info(infos, info, i)
        else:
            infos = self._finish_each(stepping, rewards, terminated, truncated)
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            self._autoreset = terminated | truncated
        elif self.autoreset_mode == AutoresetMode.DISABLED:
            self._autoreset[:] = False
            for k in np.flatnonzero(terminated | truncated):
                self.episodes[k].done = True
        self._attach_renderers()
        return self._obs.copy(), rewards, terminated, truncated, infos

    def _finish_together(self, stepping: list[int],
                         shared: list[tuple[Replicas, list[int], list[int]]],
                         rewards: np.ndarray, terminated: np.ndarray,
                         truncated: np.ndarray) -> dict:
        """What ``_finish_each`` does for the stepping slots, their robots read in one call
        per shared space and the task's arithmetic done on arrays (``outcomes``)."""
        first, n = self.episodes[0], self.num_envs
        parts = [shard.robot_states(first.task.name, copies)
                 for shard, copies, _ in shared if copies]
        infos: dict = {}
        if not parts:
            return infos
        states = parts[0] if len(parts) == 1 else {
            key: np.concatenate([part[key] for part in parts]) for key in parts[0]}
        tasks = [self.episodes[i].task for i in stepping]
        every = len(stepping) == n
        block = self._obs if every else self._obs[stepping]  # fancy indexing: a copy
        rewards[stepping], terminated[stepping], info = outcomes(
            tasks, states, first.control_period, first.terminate_on_collision, block)
        if not every:
            self._obs[stepping] = block
        info["time"] = states["time"]
        truncated[stepping] = ~terminated[stepping] & (states["time"] >= first.time_limit - 1e-9)
        mask = np.zeros(n, dtype=np.bool_)
        mask[stepping] = True
        for key, values in info.items():
            infos[key] = np.zeros(n, dtype=values.dtype)
            infos[key][stepping] = values
            infos[f"_{key}"] = mask.copy()
        for i in stepping:
            if terminated[i] or truncated[i]:
                episode = self.episodes[i]
                assert episode.sim is not None
                infos = self._add_info(infos, end_info(episode.sim, episode.robot_name), i)
                episode.done = True
        return infos

    def _finish_each(self, stepping: list[int], rewards: np.ndarray, terminated: np.ndarray,
                     truncated: np.ndarray) -> dict:
        """Every slot's step result (or, NEXT_STEP, its reset) slot by slot: their infos."""
        n = self.num_envs
        each: list[dict] = []
        final: list[tuple[int, dict]] = []
        moving = set(stepping)
        for i in range(n):
            episode = self.episodes[i]
            if self._autoreset[i]:  # NEXT_STEP: this step is the reset
                self._obs[i], info = episode.reset(self._rngs[i])
            elif i not in moving:  # DISABLED: ended, waiting for its reset
                info = {}
            else:
                (self._obs[i], rewards[i], terminated[i], truncated[i],
                 info) = episode.finish(self._obs[i])
                if self.autoreset_mode == AutoresetMode.SAME_STEP and (terminated[i] or
                                                                       truncated[i]):
                    final.append((i, {"final_obs": self._obs[i].copy(), "final_info": info}))
                    self._obs[i], info = episode.reset(self._rngs[i])
            each.append(info)
        infos = self._gather_infos(each)
        for i, info in final:
            infos = self._add_info(infos, info, i)
        return infos

    def _command(self, clipped: np.ndarray, stepping: list[int],
                 shared: list[tuple[Replicas, list[int], list[int]]]) -> None:
        """Each stepping slot's checked, clipped action to its robot: as ``task.command``
        does slot by slot, one call per shared space for a diff drive's (v, omega)."""
        task = self.episodes[0].task
        if not self._shards or task.holonomic:
            rows = clipped.tolist()
            for i in stepping:
                self.episodes[i].task.command(rows[i])
            return
        for shard, copies, chosen in shared:
            shard.set_velocities(task.name, copies, clipped[chosen, 0] * task.v_max,
                                 clipped[chosen, 1] * task.omega_max)
            for slot in chosen:  # each slot's next observation shows the action it took
                self.episodes[slot].task.previous[0] = clipped[slot]

    def _stepping_copies(self, stepping: list[int]) -> list[tuple[Replicas, list[int], list[int]]]:
        """Per shared space: the copies whose slots are stepping, and those slots (none
        without shared spaces)."""
        moving = set(stepping)
        out = []
        for shard, slots in zip(self._shards, self._slots):
            copies = [c for c, slot in enumerate(slots) if slot in moving]
            out.append((shard, copies, [slots[c] for c in copies]))
        return out

    def _gather_infos(self, each: list[dict]) -> dict:
        """Gymnasium's dict of arrays (each key with its ``_key`` mask) from every env's info:
        what ``_add_info`` env by env gives, with the keys every env has in one array each."""
        n, infos = self.num_envs, {}
        scalars = (int, float, bool, np.bool_, np.integer, np.floating)
        for key, value in each[0].items():
            if isinstance(value, scalars):
                values = [info.get(key) for info in each]
                if len(set(map(type, values))) == 1:  # one kind in every env
                    infos[key] = np.array(values, dtype=type(value))
                    infos[f"_{key}"] = np.ones(n, dtype=np.bool_)
        gathered = len(infos) // 2
        for i, info in enumerate(each):
            if len(info) > gathered:  # keys only some envs have (e.g. "result" at an end)
                infos = self._add_info(infos, {k: v for k, v in info.items()
                                               if k not in infos}, i)
        return infos

    def _share_spaces(self, first: NavigationEpisode) -> list[Replicas]:
        """The worlds as copies sharing spaces (MAX_REPLICAS to a space), when the scenario
        allows it (its actors keep to their own copy); else none: each world keeps a space
        of its own."""
        n = len(self.episodes)
        count = -(-n // MAX_REPLICAS)
        slots = [list(range(k * n // count, (k + 1) * n // count)) for k in range(count)]
        try:
            shards = [Replicas(first.config, [0] * len(members), first.source)
                      for members in slots]
        except NotShareable:
            return []
        for shard, members in zip(shards, slots):
            for index, slot in enumerate(members):
                self.episodes[slot].share(shard, index)
        self._slots = slots  # each shard's env slots, in copy order
        return shards

    def render(self) -> tuple[np.ndarray, ...] | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode='rgb_array'")
            return None
        if self._renderers is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        return tuple(r.rgb() for r in self._renderers)

    def _attach_renderers(self) -> None:
        if self._renderers is not None and any(r.sim is not e.sim for r, e in
                                               zip(self._renderers, self.episodes)):
            self.close_extras()  # worlds drawn per episode (randomize): new views
        if self.render_mode is not None and self._renderers is None:
            from pymunk_bot.envs.render import FrameRenderer

            self._renderers = [FrameRenderer(e.sim, agents=[e.robot_name])
                               for e in self.episodes]

    def close_extras(self, **kwargs: Any) -> None:
        for renderer in self._renderers or []:
            renderer.close()
        self._renderers = None
