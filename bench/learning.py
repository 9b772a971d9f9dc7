"""Learning and sweep throughput (`python -m bench.learning`, or `run(quick)`):

1. one Navigation-v0 env (180-beam LiDAR, 10 Hz control) against the same loop written on
   bare pymunk: the same world and robot (its kinematic control body, pivot and gear joints),
   the same 180 beams cast with ``segment_query_first``, the same observation;
2. the native vector env against N single envs (``gym.make``) stepped one after another,
   every robot on a steady arc, and with random actions;
3. a sweep of 200 runs on the serial, process and Dask (local cluster) backends.

Environment figures are CPU time of this process (``time.process_time``); sweep figures are
wall time, since their work runs in other processes.
"""
from __future__ import annotations

import math
import statistics
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

ACTION = np.array([0.6, 0.3], np.float32)  # a steady arc: the robot keeps meeting things


def _env_kwargs(beams: int = 180) -> dict:
    # A long episode so the timed loop never resets; LiDAR noise on, as in the default scenario.
    return {"scenario": None, "lidar": {"beams": beams}, "max_episode_time": 3600.0}


def env_steps_per_second(steps: int = 600, beams: int = 180) -> float:
    from pymunk_bot.envs import NavigationEnv

    env = NavigationEnv(**_env_kwargs(beams))
    env.reset(seed=0)
    started = time.process_time()
    for _ in range(steps):
        env.step(ACTION)
    return steps / (time.process_time() - started)


def bare_pymunk_steps_per_second(steps: int = 600, beams: int = 180) -> float:
    """The env's loop by hand on bare pymunk: command the control body every substep, step
    the space, cast every beam with ``segment_query_first``, build the same observation."""

    from pymunk_bot.envs import NavigationEnv
    from pymunk_bot.policy.io import GOAL_SCALE, PROXIMITY_SCALE

    env = NavigationEnv(**_env_kwargs(beams))
    env.reset(seed=0)  # only to build the identical world; the loop below never calls it
    sim, task = env.sim, env.episode.task
    if sim is None:
        raise RuntimeError("NavigationEnv.reset() did not build a simulation")
    robot = sim.robots[task.name]
    space, body = sim.world.space, robot.body
    control = robot.control  # the kinematic body the pivot and gear joints pull on
    h = sim.dt / sim.substeps
    substeps = env.episode.steps_per_action * sim.substeps
    angles = robot.lidar.angles
    max_range = robot.lidar.config.max_range
    shape_filter = robot.shape.filter
    goal = robot.goal
    if goal is None:
        raise RuntimeError(f"robot '{task.name}' has no goal: the observation needs one")
    v, omega = ACTION[0] * task.v_max, ACTION[1] * task.omega_max
    near = PROXIMITY_SCALE / max_range  # proximity = near * (R - r) / (s + r), 0 for no return
    obs = np.empty(beams + 8, np.float32)
    started = time.process_time()
    for _ in range(steps):
        for _ in range(substeps):
            heading = body.angle + 0.5 * omega * h
            control.velocity = (v * math.cos(heading), v * math.sin(heading))
            control.angular_velocity = omega
            space.step(h)
        x, y = body.position
        theta = body.angle
        closest, closest_angle = 0.0, 0.0
        for i, a in enumerate(angles):
            end = (x + max_range * math.cos(theta + a), y + max_range * math.sin(theta + a))
            hit = space.segment_query_first((x, y), end, 0.0, shape_filter)
            r = max_range if hit is None else hit.alpha * max_range
            obs[i] = proximity = near * (max_range - r) / (PROXIMITY_SCALE + r)
            if proximity > closest:
                closest, closest_angle = proximity, a
        obs[beams], obs[beams + 1], obs[beams + 2] = (closest, math.cos(closest_angle),
                                                      math.sin(closest_angle))
        distance = math.hypot(goal[0] - x, goal[1] - y)
        bearing = math.atan2(goal[1] - y, goal[0] - x) - theta
        obs[beams + 3] = distance / (distance + GOAL_SCALE)
        obs[beams + 4], obs[beams + 5] = math.cos(bearing), math.sin(bearing)
        obs[beams + 6], obs[beams + 7] = ACTION  # the previous action
    return steps / (time.process_time() - started)


def vector_vs_separate(num_envs: int = 16, steps: int = 10, repeats: int = 25,
                       random_actions: bool = False) -> tuple[float, float, float]:
    """(env steps per second of the native vector env, of ``num_envs`` gym.make envs stepped
    one after another, ratio of the two). Blocks of ``steps`` steps alternate between them,
    ``repeats`` times; the rates are medians over the blocks and the ratio is the median of
    each pair of neighbouring blocks' ratios (short pairs: the VM's speed drifts between
    them less). Every robot drives a steady arc, or with ``random_actions`` a new uniform
    random action every step (the same for both sides)."""
    import gymnasium as gym

    import pymunk_bot.envs  # noqa: F401

    kwargs = _env_kwargs()
    vec = gym.make_vec("pymunk_bot/Navigation-v0", num_envs=num_envs,
                       vectorization_mode="vector_entry_point", **kwargs)
    vec.reset(seed=0)
    envs = [gym.make("pymunk_bot/Navigation-v0", **kwargs) for _ in range(num_envs)]
    for i, env in enumerate(envs):
        env.reset(seed=i)
    draw = np.random.default_rng(0)
    vector_rates, separate_rates = [], []
    for _ in range(repeats):
        block = (draw.uniform(-1.0, 1.0, (steps, num_envs, 2)).astype(np.float32)
                 if random_actions else np.tile(ACTION, (steps, num_envs, 1)))
        started = time.process_time()
        for actions in block:
            vec.step(actions)
        vector_rates.append(num_envs * steps / (time.process_time() - started))
        started = time.process_time()
        for actions in block:
            for env, action in zip(envs, actions):
                env.step(action)
        separate_rates.append(num_envs * steps / (time.process_time() - started))
    ratios = [v / s for v, s in zip(vector_rates, separate_rates)]
    return (statistics.median(vector_rates), statistics.median(separate_rates),
            statistics.median(ratios))


def vector_rate(num_envs: int = 16, steps: int = 50, repeats: int = 15,
                episode: float | None = None) -> float:
    """Env steps per CPU second of the native vector env with a new uniform random action
    every step, stepped on its own as a training loop steps it (the median of ``repeats``
    blocks of ``steps`` steps, after a warm-up block). ``vector_vs_separate`` interleaves
    blocks of 16 single envs, whose cache traffic slows the vector env's blocks by ~8 %: right
    for their ratio, not for the rate a user sees. ``episode``: episodes of that many seconds
    [s] (each copy then resets every ``episode`` x 10 steps, its resets timed too), else
    an hour (no reset)."""
    import gymnasium as gym

    import pymunk_bot.envs  # noqa: F401

    kwargs = _env_kwargs()
    if episode is not None:
        kwargs["max_episode_time"] = episode
    vec = gym.make_vec("pymunk_bot/Navigation-v0", num_envs=num_envs,
                       vectorization_mode="vector_entry_point", **kwargs)
    vec.reset(seed=0)
    draw = np.random.default_rng(0)
    rates = []
    for block in range(repeats + 1):
        actions = draw.uniform(-1.0, 1.0, (steps, num_envs, 2)).astype(np.float32)
        started = time.process_time()
        for action in actions:
            vec.step(action)
        if block:  # the first block warms up
            rates.append(num_envs * steps / (time.process_time() - started))
    vec.close()
    return statistics.median(rates)


def sweep_scenario() -> dict:
    """A short run (2 s simulated) with a LiDAR-driven controller: ~10 ms of work per run."""
    return {"name": "bench_sweep", "world": {"size": [6.0, 3.0], "duration": 2.0},
            "obstacles": [{"type": "box", "center": [3.0, 1.0], "size": [0.5, 0.5]}],
            "robots": [{"name": "r1", "pose": [0.5, 1.5, 0.0],
                        "lidar": {"beams": 90, "noise_std": 0.01},
                        "controller": {"type": "avoid"},
                        "goal": {"position": [5.5, 1.5]}}]}


def sweep_backends(runs: int = 200, backends: Sequence[str] = ("serial", "process", "dask"),
                   workers: int = 2) -> list[dict[str, Any]]:
    """Wall time of the same sweep per backend, chunked automatically and one run per task;
    the difference between the two gives the backend's overhead per task."""
    from pymunk_bot.sweep import chunk_runs, run_sweep
    from pymunk_bot.sweep.grid import Run

    grid = {"robots[0].max_wheel_speed": [0.5, 1.0]}
    seeds = range(runs // 2)
    rows: list[dict[str, Any]] = []
    serial_wall: float | None = None
    for backend in backends:
        n = 1 if backend == "serial" else workers
        auto_tasks = len(chunk_runs([Run(i, (), 0) for i in range(runs)], n))
        walls: dict[int | None, float] = {}
        for chunk_size in (None, 1) if backend != "serial" else (None,):
            started = time.perf_counter()
            try:
                run_sweep(sweep_scenario(), grid, seeds, backend=backend, workers=workers,
                          chunk_size=chunk_size)
            except Exception as exc:  # a missing extra: say so, measure the rest
                rows.append({"backend": backend, "error": str(exc)})
                break
            walls[chunk_size] = time.perf_counter() - started
        if None not in walls:
            continue
        serial_wall = walls[None] if backend == "serial" else serial_wall
        if serial_wall is None:
            raise RuntimeError("the serial backend must be measured first: speedups are "
                               "relative to it")
        per_task = ((walls[1] - walls[None]) / (runs - auto_tasks) if 1 in walls else 0.0)
        rows.append({"backend": backend, "runs": runs, "tasks": auto_tasks,
                     "wall_s": walls[None], "speedup": serial_wall / walls[None],
                     "wall_one_run_per_task_s": walls.get(1, walls[None]),
                     "overhead_per_task_ms": 1e3 * per_task})
    return rows


ENV_TARGET = 3.0  # issue 12: one env >= 3x the same loop on bare pymunk
VECTOR_TARGET = 2.0  # issue 12: 16 envs as one vector env >= 2x 16 separate envs
# Issues 23 and 32 gave these in a machine's numbers: one env >= 3,000 env steps/s, the 16-env
# vector env with random actions >= 10,000. Here they are ratios against the env's loop by hand
# on bare pymunk (bare_pymunk_steps_per_second) in the same run, so the verdicts hold on any
# machine: that loop made BARE_RATE_HERE env steps per CPU second on the machine they were
# carried over on (2026-12-05, the project's 2-core machine), so 3,000 is 3000 / BARE_RATE_HERE
# of it (below ENV_TARGET: the ratio above is the stricter demand) and 10,000 is VECTOR_RATE_RATIO.
BARE_RATE_HERE = 1_470.0  # [env steps per CPU second]
VECTOR_RATE_RATIO = 10_000.0 / BARE_RATE_HERE  # the vector env's rate / the bare loop's, at least
SHORT_EPISODE = 5.0  # [s] episodes that end while a training loop runs: resets timed too
SCALING_TARGET = 1.8  # issue 23: the process sweep on 2 workers against serial
# Runs of the scaling sweep (about a minute serial): starting a worker costs about 1 s (0.6 s
# of imports, 0.3 s for numba to load its compiled code), which a short sweep cannot amortise
# (measured: 1.23x with 200 runs, 1.66x with 1,000, 1.84-1.91x with 2,000, 1.95x with 4,000).
SCALING_RUNS = 4000


def run(quick: bool = False) -> dict:
    """Every measurement, printed; returns them (what `pymunk-bot bench` calls). The env and
    its bare-pymunk twin alternate, and the ratio is the median of each pair's (the VM's speed
    drifts less within a pair than across the run)."""
    repeats = 3 if quick else 7
    envs, bares = [], []
    for _ in range(repeats):
        envs.append(env_steps_per_second(300 if quick else 600))
        bares.append(bare_pymunk_steps_per_second(300 if quick else 600))
    env, bare = statistics.median(envs), statistics.median(bares)
    ratio = statistics.median(e / b for e, b in zip(envs, bares))  # pair by pair: see above
    print("Navigation-v0, 180-beam LiDAR, 10 Hz control (env steps per CPU second)")
    print(f"  env {env:8.0f}   bare pymunk + "
          f"segment_query_first {bare:8.0f}   ratio {ratio:.2f}x (target >= {ENV_TARGET:g}x)")
    results: dict[str, Any] = {"env_steps_per_s": env, "bare_pymunk_steps_per_s": bare,
                               "env_ratio": ratio}
    for n, random_actions in ((16, False), (64, False), (16, True)):
        vector, separate, ratio = vector_vs_separate(n, repeats=7 if quick else 25,
                                                     random_actions=random_actions)
        key = f"vector_{n}" + ("_random" if random_actions else "")
        print(f"  {n} envs{', random actions' if random_actions else ''}: vector env "
              f"{vector:8.0f}   {n} separate envs {separate:8.0f}   ratio {ratio:.2f}x "
              "(blocks alternating)")
        results[key] = (vector, separate)
        results[f"{key}_ratio"] = ratio
    results["vector_16_random_rate"] = vector_rate(repeats=5 if quick else 15)
    results["vector_16_random_rate_ratio"] = results["vector_16_random_rate"] / bare
    print(f"  16 envs, random actions, the vector env on its own: "
          f"{results['vector_16_random_rate']:8.0f} env steps/s, "
          f"{results['vector_16_random_rate_ratio']:.2f}x the bare loop's (target >= "
          f"{VECTOR_RATE_RATIO:.2f}x)")
    results["vector_16_short_episodes_rate"] = vector_rate(repeats=5 if quick else 15,
                                                           episode=SHORT_EPISODE)
    print(f"  the same with {SHORT_EPISODE:g} s episodes (each copy reset every "
          f"{round(10 * SHORT_EPISODE)} steps): "
          f"{results['vector_16_short_episodes_rate']:8.0f} env steps/s")
    print(f"Sweep of {60 if quick else 200} runs (2 s simulated each), 2 workers "
          "(wall times include starting the workers)")
    sweep = sweep_backends(60 if quick else 200)
    for row in sweep:
        if "error" in row:
            print(f"  {row['backend']:<8} unavailable: {row['error']}")
        else:
            print(f"  {row['backend']:<8} {row['wall_s']:6.2f} s in {row['tasks']:2d} tasks "
                  f"(speedup {row['speedup']:4.2f}x); one run per task "
                  f"{row['wall_one_run_per_task_s']:6.2f} s: "
                  f"{row['overhead_per_task_ms']:5.1f} ms overhead per task")
    results["sweep"] = sweep
    if not quick:
        scaling = {row["backend"]: row for row in sweep_backends(SCALING_RUNS, ("serial", "process"))}
        if "error" not in scaling.get("process", {"error": ""}):
            results["process_scaling"] = scaling["process"]["speedup"]
            print(f"  process, {SCALING_RUNS} runs: {scaling['process']['wall_s']:.1f} s against "
                  f"{scaling['serial']['wall_s']:.1f} s serial (speedup "
                  f"{results['process_scaling']:.2f}x, target >= {SCALING_TARGET:g}x)")
    return results


def main() -> None:
    run()


if __name__ == "__main__":
    main()
