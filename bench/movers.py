"""What things that move by themselves cost: pedestrians (social force) and scripted obstacles.

    python -m bench.movers
"""
from __future__ import annotations

import statistics
import time

import numpy as np

from pymunk_bot.config import parse_scenario
from pymunk_bot.engine.simulation import Simulation


def crowd_scenario(n_walkers: int, n_movers: int = 0, seed: int = 0) -> dict:
    """A 30x30 m hall: walkers crossing it between random goals, boxes shuttling across."""
    rng = np.random.default_rng(seed)
    obstacles: list[dict] = []
    for _ in range(n_walkers):
        start, goal = rng.uniform(1.0, 29.0, size=(2, 2))
        obstacles.append({"type": "pedestrian", "center": start.tolist(),
                          "goals": [goal.tolist(), start.tolist()], "speed_std": 0.2})
    for k in range(n_movers):
        x = 2.0 + 26.0 * k / max(1, n_movers - 1)
        obstacles.append({"type": "box", "center": [x, 1.0], "size": [0.4, 0.4],
                          "motion": {"path": [[x, 1.0], [x, 29.0]], "speed": 0.8,
                                     "mode": "pingpong"}})
    obstacles = _spread(obstacles)
    robot = {"name": "r", "pose": [15.0, 15.0, 0.0], "lidar": {"beams": 360, "max_range": 10.0}}
    return {"name": "crowd", "world": {"size": [30.0, 30.0]}, "obstacles": obstacles,
            "robots": [robot]}


def _spread(obstacles: list[dict]) -> list[dict]:
    """Drop walkers that would start on another walker or on the robot."""
    kept: list[dict] = []
    for o in obstacles:
        c = np.asarray(o["center"])
        if np.hypot(*(c - 15.0)) < 0.8:
            continue
        if o["type"] == "pedestrian" and any(
                k["type"] == "pedestrian" and np.hypot(*(c - k["center"])) < 0.6 for k in kept):
            continue
        kept.append(o)
    return kept


def step_cost(scenario: dict, seconds: float = 10.0, repeats: int = 3) -> float:
    """Median wall-clock microseconds per simulation step."""
    times = []
    for _ in range(repeats):
        sim = Simulation(parse_scenario(scenario, "bench"))
        steps = round(seconds / sim.dt)
        started = time.perf_counter()
        for _ in range(steps):
            sim.step()
        times.append((time.perf_counter() - started) / steps * 1e6)
    return statistics.median(times)


def main(repeats: int = 3) -> None:
    base = step_cost(crowd_scenario(0), repeats=repeats)
    print(f"{'walkers':>8} {'movers':>7} {'us/step':>9} {'extra us/step':>14} {'real-time x':>12}")
    for walkers, movers in ((0, 0), (10, 0), (50, 0), (200, 0), (0, 20)):
        cost = step_cost(crowd_scenario(walkers, movers), repeats=repeats)
        print(f"{walkers:>8} {movers:>7} {cost:>9.0f} {cost - base:>14.0f} "
              f"{1e6 / 60 / cost:>12.1f}")


if __name__ == "__main__":
    main()
