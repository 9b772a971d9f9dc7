"""Imitation of a crowd controller (examples/train_crowd.py ``--imitate``): behaviour cloning
with DAgger rounds, the network seeing only the ``crowd_state`` observation.

A teacher (a registered robot controller, e.g. ``social_force``, which sees the LiDAR and
plans on the map) drives CrowdNav episodes of the shipped ``crowdnav`` suite on TRAINING
layouts. Every control step (0.25 s) records the crowd observation the policy would see (the
same builder the env and the ``policy`` controller use, :mod:`pymunk_bot.policy.crowd_io`)
and the teacher's command on the policy's action scale (:class:`ActionScale`). An MLP (tanh
hidden layers, linear output clipped to [-1, 1]: :class:`MlpPolicy`) is fitted to those
pairs with Adam on the squared error. DAgger (Ross et al. 2011): in the next rounds the
network drives (the teacher labels what it would do where the network went), so the clone
learns to recover from its own mistakes; all rounds' pairs are kept and refitted.

Deterministic: episodes are recorded in seed order (any worker count gives the same arrays),
the fit draws its initial weights and minibatches from one seeded numpy Generator.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

MAX_SAMPLES = 2_000_000  # observation/action pairs kept at most (memory: ~0.4 GB at 46 inputs)


@dataclass
class Demonstrations:
    """Observations (n x inputs, float32) and the teacher's actions (n x A, float64)."""

    observations: np.ndarray
    actions: np.ndarray
    successes: int  # episodes of the recording that arrived without a collision
    episodes: int


class Recorder:
    """Stands in for the robot's controller: asks the teacher at every control step, records
    (crowd observation, teacher action) and drives with the teacher's command or, when
    ``student`` is given, with the student's (DAgger)."""

    def __init__(self, teacher: Any, spec: Any, humans: int, student: Any = None) -> None:
        from pymunk_bot.policy.crowd_io import CrowdObservationBuilder
        from pymunk_bot.policy.io import ActionScale

        self.teacher = teacher
        self.rate = teacher.rate  # [Hz] the schedule the simulation built for the teacher
        self.scale = ActionScale.of(spec)
        self.builder = CrowdObservationBuilder(humans, self.scale, spec.radius)
        self.student = student
        self.previous = np.zeros((1, self.scale.size))  # the action that drove last
        self.observations: list[np.ndarray] = []
        self.actions: list[list[float]] = []

    @property
    def status(self) -> str:
        return self.teacher.status

    @property
    def message(self) -> str:
        return self.teacher.message

    def compute(self, obs: Any) -> Any:
        from pymunk_bot.policy.io import goal_features

        command = self.teacher.compute(obs)
        if self.teacher.status != "running" or obs.goal is None:
            return command  # arrived or gave up: nothing to imitate
        x, y, theta = obs.pose.tolist()
        row = np.empty((1, self.builder.size), dtype=np.float32)
        self.builder.fill(row[0], obs.pose.tolist(),
                          goal_features(x, y, theta, obs.goal[0], obs.goal[1]),
                          self.previous, obs.extra["crowd_state"])
        limits = [self.scale.v_max, self.scale.omega_max, self.scale.vy_max]
        taught = self.scale.clipped([getattr(command, name) / limit for name, limit in
                                     zip(("v", "omega", "vy"), limits) if limit is not None])
        self.observations.append(row[0])
        self.actions.append(taught)
        if self.student is None:
            self.previous[0] = taught
            return self.scale.command(taught)
        driven = self.scale.clipped(self.student.act(row)[0])
        self.previous[0] = driven
        command = self.scale.command(driven)
        if hasattr(self.teacher, "last"):
            # a crowd controller (controllers/crowd_nav.py) steers from the velocity it asked
            # last [m/s, world frame]: that is now the student's, as the observation says
            c, s = math.cos(theta), math.sin(theta)
            self.teacher.last = np.array([c * command.v - s * command.vy,
                                          s * command.v + c * command.vy])
        return command


def record_episode(teacher_block: dict, seed: int, humans: int, student: Any = None,
                   suite: str = "crowdnav") -> tuple[np.ndarray, np.ndarray, bool]:
    """One episode of ``suite``'s layout ``seed`` driven by the teacher (or the student):
    (observations, teacher actions, arrived without collision)."""
    from pymunk_bot.benchmark.suite import end_at_collision, episode_data, load_suite
    from pymunk_bot.config import parse_scenario
    from pymunk_bot.engine.simulation import Simulation

    entry = load_suite(suite)[0]
    data = episode_data(entry, seed)
    robots = [dict(r) for r in data["robots"]]
    robots[0]["controller"] = dict(teacher_block)
    config = parse_scenario(dict(data, robots=robots), entry.source, base_dir=entry.base_dir)
    sim = Simulation(config, seed=seed, source=entry.source)
    robot = sim.robots[config.robots[0].name]
    recorder = Recorder(robot.controller, robot.spec, humans, student)
    robot.controller = recorder
    stop_at_collision = end_at_collision(entry)
    for _ in range(round(config.world.duration / config.world.dt)):
        sim.step()
        if robot.goal_reached or (stop_at_collision and robot.collisions > 0):
            break
    success = robot.goal_reached and robot.collisions == 0
    size = recorder.builder.size
    observations = np.array(recorder.observations, dtype=np.float32).reshape(-1, size)
    actions = np.array(recorder.actions, dtype=np.float64).reshape(-1, recorder.scale.size)
    return observations, actions, success


def _record_chunk(args: tuple) -> list[tuple[np.ndarray, np.ndarray, bool]]:
    teacher_block, seeds, humans, student_path = args
    student = None
    if student_path is not None:
        from pymunk_bot.policy.files import load_policy
        student = load_policy(student_path)
    return [record_episode(teacher_block, s, humans, student) for s in seeds]


def record(teacher_block: dict, seeds: list[int], humans: int, workers: int = 2,
           student_path: str | None = None) -> Demonstrations:
    """Record the episodes of ``seeds`` on ``workers`` local processes (the same arrays for
    any worker count: chunks are joined in seed order)."""
    chunks = [seeds[i:i + 8] for i in range(0, len(seeds), 8)]
    tasks = [(teacher_block, c, humans, student_path) for c in chunks]
    if workers > 1:
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(workers) as pool:
            results = [r for part in pool.map(_record_chunk, tasks) for r in part]
    else:
        results = [r for t in tasks for r in _record_chunk(t)]
    observations = np.concatenate([r[0] for r in results])
    actions = np.concatenate([r[1] for r in results])
    return Demonstrations(observations, actions, sum(r[2] for r in results), len(results))


def fit(observations: np.ndarray, actions: np.ndarray, hidden: list[int], seed: int,
        epochs: int = 40, batch: int = 256, learning_rate: float = 1e-3) -> Any:
    """An MLP (tanh hidden layers, linear outputs) fitted to ``actions`` by Adam on the mean
    squared error, minibatches of ``batch``; returns an :class:`MlpPolicy`-ready list of
    (weights, biases)."""
    rng = np.random.default_rng(seed)
    x_all = np.asarray(observations, dtype=np.float64)
    y_all = np.asarray(actions, dtype=np.float64)
    sizes = [x_all.shape[1], *hidden, y_all.shape[1]]
    params: list[np.ndarray] = []
    for n_in, n_out in zip(sizes[:-1], sizes[1:]):
        params.append(rng.normal(0.0, 1.0 / math.sqrt(n_in), (n_in, n_out)))  # weights
        params.append(np.zeros(n_out))  # biases
    moment1 = [np.zeros_like(p) for p in params]
    moment2 = [np.zeros_like(p) for p in params]
    beta1, beta2, eps, step = 0.9, 0.999, 1e-8, 0
    n = len(x_all)
    steps_per_epoch = max(1, n // batch)
    for epoch in range(epochs):
        order = rng.permutation(n)
        # the step size decays linearly to a tenth over the run: a settled final fit
        rate = learning_rate * (1.0 - 0.9 * epoch / max(1, epochs - 1))
        for b in range(steps_per_epoch):
            idx = order[b * batch:(b + 1) * batch]
            grads = _gradients(params, x_all[idx], y_all[idx])
            step += 1
            for i, g in enumerate(grads):
                moment1[i] = beta1 * moment1[i] + (1 - beta1) * g
                moment2[i] = beta2 * moment2[i] + (1 - beta2) * g * g
                m_hat = moment1[i] / (1 - beta1 ** step)
                v_hat = moment2[i] / (1 - beta2 ** step)
                params[i] -= rate * m_hat / (np.sqrt(v_hat) + eps)
    return params[0::2], params[1::2]


def mse(weights: list[np.ndarray], biases: list[np.ndarray], x: np.ndarray, y: np.ndarray
        ) -> float:
    """Mean squared error of the network on (x, y), its output clipped as the policy's is."""
    h = np.asarray(x, dtype=np.float64)
    for i, (w, b) in enumerate(zip(weights, biases)):
        h = h @ w + b
        if i < len(weights) - 1:
            h = np.tanh(h)
    return float(np.mean((np.clip(h, -1.0, 1.0) - y) ** 2))


def _gradients(params: list[np.ndarray], x: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    """Gradient of the mean squared error of the unclipped output (backpropagation)."""
    weights, biases = params[0::2], params[1::2]
    activations = [x]
    h = x
    for i, (w, b) in enumerate(zip(weights, biases)):
        h = h @ w + b
        if i < len(weights) - 1:
            h = np.tanh(h)
        activations.append(h)
    delta = 2.0 * (h - y) / y.size
    grads: list[np.ndarray] = [np.empty(0)] * len(params)
    for i in range(len(weights) - 1, -1, -1):
        grads[2 * i] = activations[i].T @ delta
        grads[2 * i + 1] = delta.sum(axis=0)
        if i > 0:
            delta = (delta @ weights[i].T) * (1.0 - activations[i] ** 2)
    return grads


def cpu_seconds() -> float:
    """CPU time [s] of this process and its finished worker processes."""
    import resource

    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def success_rate(policy_path: str, seeds: list[int], workers: int = 2,
                 suite: str = "crowdnav") -> float:
    """Success without collision of the policy file on ``suite``'s layouts ``seeds``, run as
    the benchmark runs it (the ``policy`` controller at 4 Hz, as crowdnav_policy.yaml)."""
    from pathlib import Path

    from pymunk_bot.benchmark.controllers import ControllerChoice
    from pymunk_bot.benchmark.runner import run_benchmark
    from pymunk_bot.benchmark.suite import load_suite

    path = Path(policy_path).resolve()
    choice = ControllerChoice("student", {"type": "policy", "path": path.name, "rate": 4.0,
                                          "give_up_after": 25.0}, str(path.parent))
    rows = run_benchmark(load_suite(suite), [choice], seeds, backend="process",
                         workers=workers)
    return float(np.mean([r["success"] for r in rows]))


def imitate(teacher: dict, out: Any, humans: int, hidden: list[int], seed: int, demos: int,
            rounds: int, round_episodes: int, epochs: int, workers: int, train_layouts: list[int],
            validation_seeds: list[int]) -> list[dict]:
    """Clone ``teacher`` (a controller block) into the policy file ``out``: ``demos`` teacher
    episodes, then ``rounds`` DAgger rounds of ``round_episodes`` student episodes each, the
    network refitted on everything after each; the student's validation success after each
    fit (the history returned). Layout seeds are consecutive from ``train_layouts[0]``."""
    from pymunk_bot.policy.files import MlpPolicy

    block = dict(teacher, rate=4.0)  # the teacher acts at the policy's step, 0.25 s
    start = cpu_seconds()
    first = train_layouts[0]
    seeds = list(range(first, first + demos))
    data = record(block, seeds, humans, workers)
    print(f"teacher {teacher}: {data.successes}/{data.episodes} episodes succeeded, "
          f"{len(data.observations)} pairs", flush=True)
    x, y = data.observations, data.actions
    history: list[dict] = []
    next_seed = first + demos
    for round_ in range(rounds + 1):
        if round_ > 0:
            seeds = list(range(next_seed, next_seed + round_episodes))
            next_seed += round_episodes
            if next_seed > train_layouts[1]:
                raise ValueError("more episodes than training layouts")
            more = record(block, seeds, humans, workers, student_path=str(out))
            x, y = np.concatenate([x, more.observations]), np.concatenate([y, more.actions])
            x, y = x[-MAX_SAMPLES:], y[-MAX_SAMPLES:]
            print(f"DAgger round {round_}: the student drove {more.successes}/"
                  f"{more.episodes} home, {len(x)} pairs in all", flush=True)
        weights, biases = fit(x, y, hidden, seed + round_, epochs)
        MlpPolicy(weights, biases, crowd_humans=humans).save(out)
        entry = {"round": round_, "pairs": len(x), "mse": mse(weights, biases, x, y),
                 "validation": success_rate(str(out), validation_seeds, workers),
                 "cpu_minutes": (cpu_seconds() - start) / 60}
        history.append(entry)
        print(f"round {round_}: {entry['pairs']} pairs, fit mse {entry['mse']:.4f}, "
              f"validation success {entry['validation']:.3f}", flush=True)
    return history
