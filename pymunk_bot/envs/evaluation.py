"""A trained policy's episodes in Navigation-v0 and their statistics with 95 % confidence
intervals: what ``pymunk-bot evaluate`` prints and ``examples/train_es.py`` reports.

Episode k is ``env.reset(seed=seed + k)``: the same seeds give the same episodes, on one
process or many. A policy stepped in the env drives exactly as the ``policy`` controller does
in a scenario (tests/policy), so these figures hold for the controller too.
"""
from __future__ import annotations

import json
import math
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pymunk_bot.policy.files import (
    Policy, PolicyFileError, check_guidance, check_observation, load_policy,
)

MAX_EPISODES = 100_000
Z95 = 1.959963984540054  # two-sided 95 % normal quantile
MAX_KEPT_ENVS = 4  # envs one process keeps for kept_env (each holds the worlds it generated)
_kept_envs: dict[str, Any] = {}  # this process's kept envs, by their arguments, oldest first


@dataclass(frozen=True)
class EpisodeOutcome:
    """One episode: its seed, whether it arrived (with no contact on the way: ``success``),
    seconds in contact, contact episodes, time to goal [s] (NaN: not reached), return."""

    seed: int
    reached: bool
    success: bool
    contact_time: float
    collisions: int
    time_to_goal: float
    episode_return: float


def run_episodes(policy: Policy | str | Path, env_kwargs: dict[str, Any] | None,
                 seeds: list[int], env: Any = None) -> list[EpisodeOutcome]:
    """Play the policy (or the policy file) for one episode per seed, in ``env`` if given
    (kept open: a trainer reuses it, and its generated worlds) or a new env of ``env_kwargs``;
    PolicyFileError if the policy returns a NaN or infinite action or fails to run, or records
    that it was trained with plan guidance and the env has none (or the reverse), or on another
    observation than the env's."""
    from pymunk_bot.envs.navigation import NavigationEnv

    agent = load_policy(policy) if isinstance(policy, (str, Path)) else policy
    own = env is None
    if env is None:
        env = NavigationEnv(**(env_kwargs or {}))
    try:
        check_guidance(agent, env.episode.task.plan_guidance)
        check_observation(agent, env.episode.task.observation)
    except PolicyFileError:
        if own:
            env.close()
        raise
    outcomes = []
    for seed in seeds:
        obs, _ = env.reset(seed=int(seed))
        total, done = 0.0, False
        info: dict[str, Any] = {}
        while not done:
            action = agent.act(obs[None])[0]
            if not np.isfinite(action).all():
                raise PolicyFileError(f"returned the action {np.array2string(action)} in the "
                                      f"episode of seed {seed}: not finite numbers")
            obs, reward, terminated, truncated, info = env.step(action)
            total += reward
            done = terminated or truncated
        reached = bool(info["goal_reached"])
        outcomes.append(EpisodeOutcome(int(seed), reached, bool(info["is_success"]),
                                       float(info["contact_time"]), int(info["collisions"]),
                                       float(info["time"]) if reached else math.nan, total))
    if own:
        env.close()
    return outcomes


def kept_env(env_kwargs: dict[str, Any]) -> Any:
    """A ``NavigationEnv(**env_kwargs)`` made once per process and kept, with the worlds it
    generates, for every later call with the same arguments: a trainer's job that evaluates
    one candidate reuses it on whichever worker (a local process, a Dask or Ray worker) it
    lands, as ``run_episodes(..., env=kept_env(kwargs))``. An episode depends only on its seed,
    not on what the env played before. At most MAX_KEPT_ENVS are kept (the oldest is closed)."""
    from pymunk_bot.envs.navigation import NavigationEnv

    key = json.dumps(env_kwargs, sort_keys=True, default=repr)
    if key not in _kept_envs:
        if len(_kept_envs) >= MAX_KEPT_ENVS:
            _kept_envs.pop(next(iter(_kept_envs))).close()
        _kept_envs[key] = NavigationEnv(**env_kwargs)
    return _kept_envs[key]


def release_kept_envs() -> None:
    """Close every env :func:`kept_env` keeps in this process."""
    while _kept_envs:
        _kept_envs.popitem()[1].close()


def evaluate_policy(policy: Policy | str | Path, env_kwargs: dict[str, Any], episodes: int,
                    seed: int = 0, workers: int = 1) -> list[EpisodeOutcome]:
    """Episodes ``seed`` .. ``seed + episodes - 1``, split over ``workers`` processes."""
    if not (isinstance(episodes, int) and 0 < episodes <= MAX_EPISODES):
        raise ValueError(f"episodes must be in [1, {MAX_EPISODES}] (got {episodes!r})")
    seeds = [seed + k for k in range(episodes)]
    workers = max(1, min(int(workers), episodes))
    if workers == 1:
        return run_episodes(policy, env_kwargs, seeds)
    chunks = [seeds[k::workers] for k in range(workers)]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        parts = list(pool.map(run_episodes, [policy] * workers, [env_kwargs] * workers, chunks))
    return sorted((o for part in parts for o in part), key=lambda o: o.seed)


def wilson(k: int, n: int) -> tuple[float, float]:
    """95 % Wilson score interval of a rate of ``k`` in ``n``."""
    p, z2 = k / n, Z95 * Z95
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    # At k = 0 (or n) the exact end is 0 (1): rounding left it a few 1e-17 off, outside [0, p]
    return (0.0 if k == 0 else max(0.0, centre - half)), (1.0 if k == n else min(1.0, centre + half))


def mean_interval(values: list[float]) -> tuple[float, float, float]:
    """(mean, low, high): the mean with a 95 % normal interval (NaN for no values)."""
    if not values:
        return math.nan, math.nan, math.nan
    mean = float(np.mean(values))
    if len(values) < 2:
        return mean, math.nan, math.nan
    half = Z95 * float(np.std(values, ddof=1)) / math.sqrt(len(values))
    return mean, mean - half, mean + half


def summarize(outcomes: list[EpisodeOutcome]) -> dict[str, Any]:
    """Rates (with Wilson intervals) and means (with normal intervals) of the episodes."""
    n = len(outcomes)
    summary: dict[str, Any] = {"episodes": n}
    for key, count in (("success", sum(o.success for o in outcomes)),
                       ("reached", sum(o.reached for o in outcomes)),
                       ("contact", sum(o.contact_time > 0 or o.collisions > 0 for o in outcomes))):
        low, high = wilson(count, n)
        summary[key] = {"rate": count / n, "low": low, "high": high}
    for key, values in (("collisions", [float(o.collisions) for o in outcomes]),
                        ("contact_time", [o.contact_time for o in outcomes]),
                        ("time_to_goal", [o.time_to_goal for o in outcomes if o.reached])):
        mean, low, high = mean_interval(values)
        summary[key] = {"mean": mean, "low": low, "high": high}
    return summary


def format_summary(summary: dict[str, Any]) -> str:
    """The summary as lines of text (rates in %, times in s)."""
    lines = [f"episodes: {summary['episodes']}"]
    labels = {"success": "contact-free success", "reached": "goal reached",
              "contact": "episodes with contact"}
    for key, label in labels.items():
        s = summary[key]
        lines.append(f"{label + ':':24s}{s['rate']:7.1%}   (95 % CI {s['low']:.1%} - {s['high']:.1%})")
    units = {"collisions": ("contact episodes / episode", ""),
             "contact_time": ("seconds in contact / ep.", " s"),
             "time_to_goal": ("time to goal", " s")}
    for key, (label, unit) in units.items():
        s = summary[key]
        lines.append(f"{label + ':':24s}{s['mean']:7.2f}{unit}  (95 % CI {s['low']:.2f} - "
                     f"{s['high']:.2f})")
    return "\n".join(lines)


def outcome_rows(outcomes: list[EpisodeOutcome]) -> list[dict[str, Any]]:
    """One dict per episode (for a CSV)."""
    return [asdict(o) for o in outcomes]
