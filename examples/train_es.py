"""Train a navigation policy with CMA-ES on pymunk_bot/Navigation-v0, on a laptop CPU.

    pip install 'pymunk-bot[rl,es]'
    python examples/train_es.py --minutes 10 --workers 2 --seed 0 \\
        --out clutter_es.npz --plot learning_curve.png
    python examples/train_es.py --evaluate clutter_es.npz --episodes 200
    python examples/train_es.py --generations 150 --backend dask --address SCHEDULER:8786

With ``--generations`` the same seed gives the same policy, bit for bit, on every backend
(``process``, ``dask``, ``ray``) and worker count: every random draw (CMA's samples, each
generation's episode seeds) is made here from ``--seed``, and the candidates' results are taken
in candidate order, never in the order the workers finish them.

Every episode is a generated cluttered world (``pymunk-bot generate clutter``, 8 x 6 m, its seed
drawn per episode from 200), a random free start pose and a random goal: the policy learns to
navigate, not one layout. The policy is an MLP with 8 tanh units (``--hidden 0``: linear) on
the env's observation (proximity of 32 LiDAR beams, the nearest return, the goal, the previous
action), saved as the ``.npz`` the ``policy`` controller runs. Fitness: the env's return (progress, contact-free
arrival, a cost per second in contact and near obstacles), episodes ending at the first contact,
averaged over the same episodes for every candidate of a generation. Held-out evaluation uses
world seeds training never draws.

``--plan-guidance`` trains (and evaluates) with plan-guided goal features (docs/learning.md,
"Plan guidance"): the goal the policy sees lies along an A* path on the world's map; the saved
``.npz`` records it, so ``pymunk-bot evaluate`` and the ``policy`` controller turn it on.
``--generate office`` or ``maze`` draws that kind of world instead of clutter; a list
(``--generate clutter,office,maze``) draws one of the kinds per episode, each at its own default
size, and ``--maps FILE ...`` adds ROS maps (random free starts and goals on them) to the draw.
The general policy shipped as ``scenarios/policies/navigator.npz`` is (docs/learning.md)::

    python examples/train_es.py --plan-guidance --generate clutter,office,maze \
        --maps maps/office.yaml --minutes 20 --workers 2 --seed 0 --out navigator.npz
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np

ROBOT = {"name": "r1", "pose": [1.0, 1.0, 0.0], "radius": 0.2, "max_wheel_speed": 0.8,
         "localization": "ground_truth",
         "lidar": {"beams": 32, "max_range": 4.0, "noise_std": 0.01},
         "goal": {"position": [2.0, 2.0], "tolerance": 0.25}}
SIZE = [8.0, 6.0]  # [m] of every generated world
SCENARIO = {"name": "es_clutter", "world": {"size": SIZE, "duration": 30.0}, "robots": [ROBOT]}
TRAIN_WORLDS = [0, 200]  # generated-world seeds training draws from (each drawn once, cached)
HELD_OUT_WORLDS = [1_000_000, 2_000_000]  # never seen in training
# The env's reward with a steeper clearance cost (default -1 per second at contact): the
# policy learns to slow down and keep off obstacles rather than graze them at full speed.
TRAIN_REWARD = {"clearance": -3.0}
TRAIN_SECONDS = 20.0  # [s] of a training episode with several families
HELD_OUT_SECONDS = 60.0  # [s] of a held-out episode with several families
MAX_GENERATIONS = 100_000
MAX_MINUTES = 10_080  # a week of training


def env_kwargs(worlds: list[int], training: bool, guided: bool = False,
               kind: str = "clutter", maps: tuple[str, ...] = ()) -> dict:
    """Navigation-v0's arguments: random goals, starts and generated worlds of ``kind`` (a
    comma-separated list: one drawn per episode, each at its default size; one kind: 8 x 6 m),
    and the ROS ``maps`` drawn among them; ``guided``: plan-guided goal features. Training ends
    an episode at the first contact and after TRAIN_SECONDS; held-out episodes run on through
    contacts for up to HELD_OUT_SECONDS."""
    kinds = kind.split(",")
    several = len(kinds) > 1 or bool(maps)
    randomize: dict = {"generate": kinds if several else kind, "world_seeds": worlds,
                       "start": True}
    if not several:
        randomize["size"] = SIZE
    if maps:
        randomize["maps"] = list(maps)
    return {"scenario": SCENARIO, "random_goal": True, "terminate_on_collision": training,
            "max_episode_time": (TRAIN_SECONDS if several else 20.0) if training
            else (HELD_OUT_SECONDS if several else 30.0), "reward": TRAIN_REWARD,
            "randomize": randomize, "plan_guidance": True if guided else None}


def shapes(inputs: int, hidden: int, outputs: int = 2) -> list[tuple[int, int]]:
    sizes = [inputs] + ([hidden] if hidden else []) + [outputs]
    return list(zip(sizes[:-1], sizes[1:]))


def to_policy(theta: np.ndarray, layer_shapes: list[tuple[int, int]], guided: bool = False,
              crowd_humans: int | None = None):
    """The MLP whose weights and biases are ``theta`` (layer after layer, W then b); ``guided``:
    it records the default plan guidance it was trained with; ``crowd_humans``: it records
    the crowd_state observation of that many humans it was trained on."""
    from pymunk_bot.config.guidance import PlanGuidanceConfig
    from pymunk_bot.policy.files import MlpPolicy

    weights, biases, k = [], [], 0
    for n_in, n_out in layer_shapes:
        weights.append(theta[k:k + n_in * n_out].reshape(n_in, n_out))
        k += n_in * n_out
        biases.append(theta[k:k + n_out])
        k += n_out
    return MlpPolicy(weights, biases, PlanGuidanceConfig() if guided else None, crowd_humans)


def fitness(job: tuple) -> tuple[float, float]:
    """(mean return, contact-free success rate) of parameters ``theta`` over ``seeds``, on
    the worker's kept env of ``kwargs`` (it keeps the generated worlds it drew)."""
    from pymunk_bot.envs.evaluation import kept_env, run_episodes

    theta, layer_shapes, seeds, kwargs, guided, crowd_humans = job
    runs = run_episodes(to_policy(theta, layer_shapes, guided, crowd_humans), None, seeds,
                        env=kept_env(kwargs))
    return (float(np.mean([r.episode_return for r in runs])),
            float(np.mean([r.success for r in runs])))


def episode_seeds(seed: int, generation: int, episodes: int) -> list[int]:
    """The training episodes' seeds of ``generation`` (the same for all its candidates): a
    function of the run's seed, the generation and the episode's index alone."""
    state = np.random.SeedSequence([seed, generation]).generate_state(episodes, np.uint32)
    return [int(s) >> 1 for s in state]  # 31 bits, as env seeds have always been


def train(minutes: float | None, seed: int = 0, hidden: int = 8, popsize: int = 16,
          episodes: int = 8, sigma: float = 0.3, workers: int = 2, progress: bool = True,
          generations: int | None = None, backend: str = "process", address: str | None = None,
          guided: bool = False, kind: str = "clutter", maps: tuple[str, ...] = (),
          train_env: dict | None = None, crowd_humans: int | None = None,
          validation: tuple[dict, list[int], int] | None = None,
          checkpoint: Callable[[dict, np.ndarray, list[tuple[int, int]]], None] | None = None
          ) -> tuple[np.ndarray, list[tuple[int, int]], list[dict]]:
    """CMA-ES for ``minutes`` of wall time and/or ``generations`` (whichever ends first; at
    least one): (mean parameters, layer shapes, per-generation history of elapsed time, mean
    and best fitness, mean success rate). Candidates are evaluated on ``backend`` (``process``:
    ``workers`` local processes; ``dask``, ``ray``: the cluster at ``address``, or a local one
    of ``workers``). With ``generations`` alone the result depends on the seed only: the same
    bits on every backend, worker count and machine. ``guided``: plan-guided goal features;
    ``kind``: the generated worlds' (comma-separated: several); ``maps``: ROS maps drawn
    among them. ``train_env``: the training env's arguments instead (another task, e.g.
    examples/train_crowd.py's); ``crowd_humans``: the policies record the crowd_state
    observation of that many humans; ``validation``: (env arguments, episode seeds, every N
    generations): the mean's contact-free success on those episodes, every N generations and
    after the last, in the history as ``validation`` (played on the same backend);
    ``checkpoint(history entry, mean, layer_shapes)`` is called at each validation: the mean
    after g generations is what ``generations=g`` returns (nothing else depends on the total)."""
    import cma
    from tqdm import tqdm

    from pymunk_bot.envs import NavigationEnv
    from pymunk_bot.sweep.backends import JobPool

    if minutes is None and generations is None:
        raise ValueError("give --minutes or --generations (or both)")

    kwargs = env_kwargs(TRAIN_WORLDS, True, guided, kind, maps) if train_env is None \
        else train_env
    probe = NavigationEnv(**kwargs)
    inputs, outputs = probe.episode.task.obs_size, probe.episode.task.action_size
    probe.close()
    layer_shapes = shapes(inputs, hidden, outputs)
    size = sum(a * b + b for a, b in layer_shapes)
    # CMA samples from its own Generator seeded here, not from numpy's global state
    samples = np.random.default_rng(np.random.SeedSequence([seed, 1]))
    es = cma.CMAEvolutionStrategy(np.zeros(size), sigma, {
        "popsize": popsize, "seed": np.nan, "verbose": -9,
        "randn": lambda *shape: samples.standard_normal(shape),
        "CMA_diagonal": size > 200})  # separable CMA for large nets: linear time per update
    history: list[dict] = []
    started = time.perf_counter()
    budget = math.inf if minutes is None else minutes * 60.0
    with JobPool(backend, workers, address, by_value=[sys.modules[__name__]]) as pool, \
            tqdm(total=generations if minutes is None else round(budget), disable=not progress,
                 unit="gen" if minutes is None else "s", desc="CMA-ES") as bar:
        while time.perf_counter() - started < budget and (generations is None
                                                          or len(history) < generations):
            seeds = episode_seeds(seed, len(history), episodes)  # the same for everyone
            candidates = es.ask()
            results = pool.map(fitness, [(np.asarray(c), layer_shapes, seeds, kwargs, guided,
                                          crowd_humans) for c in candidates])  # in order
            es.tell(candidates, [-r[0] for r in results])
            elapsed = time.perf_counter() - started
            returns = [r[0] for r in results]
            history.append({"generation": len(history) + 1, "time": elapsed,
                            "mean_return": float(np.mean(returns)),
                            "best_return": float(np.max(returns)),
                            "success": float(np.mean([r[1] for r in results]))})
            last = time.perf_counter() - started >= budget or len(history) == generations
            if validation is not None and (len(history) % validation[2] == 0 or last):
                history[-1]["validation"] = validate(pool, np.asarray(es.mean), layer_shapes,
                                                     validation, guided, crowd_humans)
                if checkpoint is not None:
                    checkpoint(history[-1], np.asarray(es.mean), layer_shapes)
            bar.update(1 if minutes is None else min(round(elapsed), bar.total) - bar.n)
            bar.set_postfix(ret=f"{history[-1]['mean_return']:.1f}",
                            ok=f"{history[-1]['success']:.2f}")
    return np.asarray(es.mean), layer_shapes, history


def validate(pool, theta: np.ndarray, layer_shapes: list[tuple[int, int]],
             validation: tuple[dict, list[int], int], guided: bool,
             crowd_humans: int | None) -> float:
    """Contact-free success rate of ``theta`` on the validation episodes, played in chunks on
    ``pool`` (the same rate whatever the chunks' order)."""
    kwargs, seeds, _ = validation
    chunks = [seeds[i:i + 10] for i in range(0, len(seeds), 10)]
    results = pool.map(fitness, [(theta, layer_shapes, chunk, kwargs, guided, crowd_humans)
                                 for chunk in chunks])
    return float(sum(r[1] * len(c) for r, c in zip(results, chunks)) / len(seeds))


def plot(history: list[dict], out: Path, title: str) -> None:
    """Learning curve: mean return and contact-free success of each generation."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    minutes = [h["time"] / 60 for h in history]
    fig, left = plt.subplots(figsize=(7, 4))
    left.plot(minutes, [h["mean_return"] for h in history], label="mean return", color="C0")
    left.plot(minutes, [h["best_return"] for h in history], label="best return", color="C0",
              alpha=0.35)
    left.set_xlabel("wall time [min]")
    left.set_ylabel("episode return")
    right = left.twinx()
    right.plot(minutes, [h["success"] for h in history], color="C2",
               label="contact-free success (population, training episodes)")
    right.set_ylim(0, 1)
    right.set_ylabel("contact-free success rate")
    lines = left.get_legend_handles_labels()
    more = right.get_legend_handles_labels()
    left.legend(lines[0] + more[0], lines[1] + more[1], loc="lower right", fontsize=8)
    left.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=None,
                        help="training wall time (default 10 without --generations)")
    parser.add_argument("--generations", type=int, default=None,
                        help="train this many generations: the same seed gives the same policy "
                             "on every backend and machine (with --minutes: whichever ends first)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--hidden", type=int, default=8, help="hidden tanh units (0: linear)")
    parser.add_argument("--popsize", type=int, default=16)
    parser.add_argument("--train-episodes", type=int, default=8,
                        help="episodes per candidate per generation")
    parser.add_argument("--workers", type=int, default=2,
                        help="local processes (process backend; dask/ray without --address)")
    parser.add_argument("--backend", choices=["process", "dask", "ray"], default="process",
                        help="where candidates are evaluated")
    parser.add_argument("--address", default=None,
                        help="HOST:PORT of the Dask scheduler or Ray head (dask/ray backends)")
    parser.add_argument("--out", type=Path, default=Path("clutter_es.npz"))
    parser.add_argument("--plot", type=Path, default=None)
    parser.add_argument("--episodes", type=int, default=200, help="held-out evaluation episodes")
    parser.add_argument("--evaluate", type=Path, default=None, help="only evaluate this .npz")
    parser.add_argument("--plan-guidance", action="store_true",
                        help="goal features along an A* path (recorded in the .npz)")
    parser.add_argument("--generate", default="clutter", metavar="KIND[,KIND...]",
                        help="the kinds of generated worlds, clutter, office or maze, "
                             "comma-separated for several (default clutter)")
    parser.add_argument("--maps", nargs="+", default=[], metavar="MAP_YAML",
                        help="ROS maps also drawn from (random free starts and goals)")
    args = parser.parse_args(argv)
    if args.minutes is None and args.generations is None:
        args.minutes = 10.0
    problem = None
    if args.minutes is not None and not 0 < args.minutes <= MAX_MINUTES:  # NaN too
        problem = (f"--minutes must be a number of minutes in (0, {MAX_MINUTES}] "
                   f"(got {args.minutes})")
    elif args.generations is not None and not 1 <= args.generations <= MAX_GENERATIONS:
        problem = f"--generations must be in [1, {MAX_GENERATIONS}] (got {args.generations})"
    elif any(k not in ("clutter", "office", "maze") for k in args.generate.split(",")):
        problem = (f"--generate takes kinds from clutter, office, maze, comma-separated "
                   f"(got '{args.generate}')")
    if problem is not None:
        print(f"error: {problem}", file=sys.stderr)
        sys.exit(2)
    from pymunk_bot.config.errors import ScenarioError
    from pymunk_bot.policy.files import MlpPolicy
    from pymunk_bot.sweep.backends import BackendUnavailable

    if args.evaluate is not None:
        policy = MlpPolicy.load(args.evaluate)
    else:
        try:
            theta, layer_shapes, history = train(
                args.minutes, args.seed, args.hidden, args.popsize, args.train_episodes,
                workers=args.workers, generations=args.generations, backend=args.backend,
                address=args.address, guided=args.plan_guidance, kind=args.generate,
                maps=tuple(args.maps))
        except (ValueError, BackendUnavailable) as exc:  # each names its option or address
            print(f"error: {exc}", file=sys.stderr)
            sys.exit(2)
        except ScenarioError as exc:  # a --maps file that is not there or not a map
            print(f"error: --maps: {exc.problem}", file=sys.stderr)
            sys.exit(2)
        policy = to_policy(theta, layer_shapes, args.plan_guidance)
        policy.save(args.out)
        print(f"{len(history)} generations in {history[-1]['time'] / 60:.1f} min; "
              f"saved {args.out}")
        if args.plot is not None:
            net = f"MLP {args.hidden} tanh units" if args.hidden else "linear"
            plot(history, args.plot, f"CMA-ES, {net}, {args.popsize} x {args.train_episodes} "
                 f"episodes per generation, {args.workers} workers, seed {args.seed}")
    from pymunk_bot.envs.evaluation import evaluate_policy, format_summary, summarize

    # Held out: worlds training never draws, and no early end at a contact; each kind apart.
    guided = policy.plan_guidance is not None  # as trained (the file records it)
    several = "," in args.generate or bool(args.maps)
    for kind in args.generate.split(","):
        kwargs = env_kwargs(HELD_OUT_WORLDS, False, guided, kind)
        if several:  # the kind's default size and the longer episodes, as in training
            kwargs["randomize"].pop("size")
            kwargs["max_episode_time"] = HELD_OUT_SECONDS
        outcomes = evaluate_policy(policy, kwargs, args.episodes, seed=10_000,
                                   workers=args.workers)
        print(f"held-out episodes in unseen generated {kind} worlds"
              f"{' (plan-guided)' if guided else ''}:")
        print(format_summary(summarize(outcomes)))

if __name__ == "__main__":
    main()
