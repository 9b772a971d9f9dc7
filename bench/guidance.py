"""What plan guidance costs (`python -m bench.guidance [--quick]`): env steps per CPU second of
Navigation-v0 with and without ``plan_guidance``, one env and a 16-env vector env, random
actions, on the default scenario and on the shipped maze (a 180-beam LiDAR, as bench.learning
measures). Blocks with and without guidance alternate in one process, and each ratio is the
median of each neighbouring pair's (the VM's speed drifts less within a pair). Replanning is
in the figures: random actions leave the path all the time (a replan at most every
``replan_period``), and every ``replan_period`` the scan is checked against the map.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

RATIO_TARGET = 1.3  # plain rate / guided rate at most this (issue 34)
SCENARIOS = (None, "maze")


def _kwargs(scenario: str | None, guided: bool) -> dict:
    return {"scenario": scenario, "lidar": {"beams": 180}, "max_episode_time": 3600.0,
            "plan_guidance": True if guided else None}


def rates(scenario: str | None, num_envs: int, steps: int, repeats: int
          ) -> tuple[float, float, float]:
    """(plain env steps per CPU second, guided, median pair ratio plain / guided)."""
    import gymnasium as gym

    import pymunk_bot.envs  # noqa: F401

    envs = {}
    for guided in (False, True):
        if num_envs == 1:
            env = gym.make("pymunk_bot/Navigation-v0", **_kwargs(scenario, guided))
        else:
            env = gym.make_vec("pymunk_bot/Navigation-v0", num_envs=num_envs,
                               vectorization_mode="vector_entry_point",
                               **_kwargs(scenario, guided))
        env.reset(seed=0)
        envs[guided] = env
    draw = np.random.default_rng(0)
    measured: dict[bool, list[float]] = {False: [], True: []}
    for block in range(repeats + 1):
        actions = draw.uniform(-1.0, 1.0, (steps, num_envs, 2)).astype(np.float32)
        for guided, env in envs.items():
            started = time.process_time()
            for action in actions:
                env.step(action[0] if num_envs == 1 else action)
            if block:  # the first block warms up (compiles, plans)
                measured[guided].append(num_envs * steps / (time.process_time() - started))
    for env in envs.values():
        env.close()
    ratio = statistics.median(p / g for p, g in zip(measured[False], measured[True]))
    return statistics.median(measured[False]), statistics.median(measured[True]), ratio


def run(quick: bool = False) -> dict:
    """Every measurement, printed and returned."""
    results = {}
    print("Navigation-v0, 180 beams, random actions: env steps per CPU second")
    for scenario in SCENARIOS:
        for num_envs, steps in ((1, 100), (16, 20)):
            plain, guided, ratio = rates(scenario, num_envs, steps, 5 if quick else 15)
            name = f"{scenario or 'default'}_{num_envs}"
            results[name] = {"plain": plain, "guided": guided, "ratio": ratio}
            print(f"  {scenario or 'default':8s} {num_envs:2d} env(s): plain {plain:7.0f}   "
                  f"guided {guided:7.0f}   {ratio:.2f}x slower (target <= {RATIO_TARGET:g}x)")
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer blocks")
    run(parser.parse_args().quick)


if __name__ == "__main__":
    main()
