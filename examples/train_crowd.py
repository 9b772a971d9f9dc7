"""Train a crowd navigation policy on CrowdNav's circle crossing with CMA-ES (train_es.py's
machinery), seeing the humans' true states: the policy on the benchmark's leaderboard.

    pip install 'pymunk-bot[rl,es]'
    python examples/train_crowd.py --generations 60 --workers 2 --seed 0 \\
        --out crowdnav.npz --plot learning_curve_crowd.png
    pymunk-bot benchmark crowdnav --controller scenarios/policies/crowdnav_policy.yaml \\
        --seeds 0:500 --out episodes.csv          # CrowdNav's 500 test cases

``--imitate CONTROLLER`` trains instead by imitation of that teacher and DAgger
(examples/crowd_imitation.py; the shipped policy: ``--imitate examples/crowd_teacher.yaml
--hidden 64 --seed 0``): docs/learning.md.

Every training episode is a CrowdNav circle crossing (the shipped ``crowdnav`` suite: 5 humans
blind to the robot, 4 m circle, 25 s, ended at the first collision) whose layout seed is drawn
from [100000, 1000000): never one of the 500 test cases (seeds 0 to 499) nor the validation
layouts ([1000000, 1100000)). The robot is the suite's (an omni disc of radius 0.3 m at
1 m/s) and acts every 0.25 s (CrowdNav's time step) on the ``crowd_state`` observation (goal,
its previous action, the 5 nearest humans in its frame: docs/learning.md); the network outputs
the velocity command itself. Fitness: CrowdNav's reward (+1 on arrival, -0.25 at a
collision, (d - 0.2) * 0.5 * dt within 0.2 m of a human), a little for progress and a small
cost of time (TRAIN_REWARD), averaged over the same episodes for every candidate of a generation.
``--generations N`` is the budget: the same seed gives the same policy on every backend.
Every ``--validate-every`` generations the mean policy plays the validation episodes: the
learning curve (``--plot``).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # train_es, beside this file

import train_es  # noqa: E402

HUMANS = 5  # the crowd_state observation's slots (CrowdNav's 5 humans)
ROBOT = {"name": "r1", "drive": "omni", "pose": [12.0, 8.0, 1.5707963267948966],
         "radius": 0.3, "max_speed": 1.0, "max_accel": 100.0, "max_angular_speed": 2.0,
         "localization": "ground_truth", "crowd_state": {"max_humans": HUMANS},
         "lidar": {"beams": 8, "max_range": 8.0},  # unused by the crowd observation
         "goal": {"position": [12.0, 16.0], "tolerance": 0.3}}
# The suite draws the room, the layout and the robot's pose. Training steps the physics at
# 20 Hz (the suite: 60 Hz): 1.35x faster per episode, and the robot (max_accel 100 m/s^2)
# still reaches each new command within one step; the policy is tested on the suite as is.
SCENARIO = {"name": "crowd_train", "world": {"size": [24.0, 24.0], "duration": 25.0,
                                             "dt": 0.05}, "robots": [ROBOT]}
TRAIN_LAYOUTS = [100_000, 1_000_000]  # layout seeds training draws (tests: 0 to 499)
VALIDATION_LAYOUTS = [1_000_000, 1_100_000]
CONTROL_PERIOD = 0.25  # [s] CrowdNav's time step
ORCA_SUCCESS = 0.428  # crowdnav_orca on the 500 test cases (docs/benchmark.md), for the plot
# CrowdNav's reward, 0.05 per metre of progress (a dense signal for the first generations,
# when nothing arrives yet: the whole crossing pays 0.4, an arrival 1) and 0.004 per second
# (of two arrivals the faster is better; a timeout, -0.1, stays better than a collision)
TRAIN_REWARD = {"progress": 0.05, "contact": 0.0, "collision": -0.25, "clearance": -0.1,
                "clearance_margin": 0.2, "time": -0.004, "success": 1.0}


def env_kwargs(layouts: list[int], suite: str = "crowdnav") -> dict:
    """Navigation-v0's arguments: CrowdNav episodes of ``suite`` with layout seeds from
    ``layouts``, the crowd observation, CrowdNav's reward, ended at the first collision."""
    return {"scenario": SCENARIO, "control_period": CONTROL_PERIOD, "max_episode_time": 25.0,
            "observation": "crowd_state", "reward": TRAIN_REWARD,
            "terminate_on_collision": True,
            "randomize": {"crowd": suite, "world_seeds": list(layouts)}}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--generations", type=int, default=60,
                        help="CMA-ES generations: the budget (the same seed, the same policy)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--hidden", type=int, default=8, help="hidden tanh units (0: linear)")
    parser.add_argument("--popsize", type=int, default=16)
    parser.add_argument("--train-episodes", type=int, default=6,
                        help="episodes per candidate per generation")
    parser.add_argument("--sigma", type=float, default=0.3, help="CMA-ES initial step size")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--backend", choices=["process", "dask", "ray"], default="process")
    parser.add_argument("--address", default=None)
    parser.add_argument("--validation-episodes", type=int, default=60)
    parser.add_argument("--validate-every", type=int, default=5,
                        help="generations between validations (and after the last)")
    parser.add_argument("--out", type=Path, default=Path("crowdnav.npz"))
    parser.add_argument("--plot", type=Path, default=None)
    parser.add_argument("--checkpoints", action="store_true",
                        help="save the mean at every validation as OUT.gN.npz")
    parser.add_argument("--imitate", default=None, metavar="CONTROLLER",
                        help="clone this teacher (a controller type or a controller file, e.g. "
                             "examples/crowd_teacher.yaml) by imitation and DAgger instead of "
                             "CMA-ES (examples/crowd_imitation.py)")
    parser.add_argument("--demos", type=int, default=400,
                        help="--imitate: teacher episodes recorded first")
    parser.add_argument("--dagger-rounds", type=int, default=4,
                        help="--imitate: rounds in which the student drives and the teacher "
                             "labels")
    parser.add_argument("--dagger-episodes", type=int, default=200,
                        help="--imitate: student episodes per DAgger round")
    parser.add_argument("--epochs", type=int, default=40,
                        help="--imitate: Adam passes over the pairs per fit")
    args = parser.parse_args(argv)
    if args.imitate is not None:
        imitate(args, parser)
        return
    problem = None
    if not 1 <= args.generations <= train_es.MAX_GENERATIONS:
        problem = (f"--generations must be in [1, {train_es.MAX_GENERATIONS}] "
                   f"(got {args.generations})")
    elif not 1 <= args.validation_episodes <= 10_000:
        problem = f"--validation-episodes must be in [1, 10000] (got {args.validation_episodes})"
    elif not 1 <= args.validate_every <= train_es.MAX_GENERATIONS:
        problem = f"--validate-every must be >= 1 (got {args.validate_every})"
    elif not 2 <= args.popsize <= 1000 or not 1 <= args.train_episodes <= 1000:
        problem = "--popsize must be in [2, 1000] and --train-episodes in [1, 1000]"
    elif not 0 < args.sigma < 100:  # NaN too
        problem = f"--sigma must be in (0, 100) (got {args.sigma})"
    if problem is not None:
        print(f"error: {problem}", file=sys.stderr)
        sys.exit(2)
    from pymunk_bot.sweep.backends import BackendUnavailable

    def checkpoint(entry: dict, theta, layer_shapes) -> None:
        """Keep the mean of every validated generation: ``OUT.gN.npz`` is what
        ``--generations N`` gives (a run stopped at a wall-clock limit keeps them)."""
        generation = entry["generation"]
        print(f"\ngeneration {generation}, {entry['time'] / 60:.1f} min: validation success "
              f"{entry['validation']:.3f}", flush=True)
        if args.checkpoints:
            path = args.out.with_suffix(f".g{generation}.npz")
            train_es.to_policy(theta, layer_shapes, crowd_humans=HUMANS).save(path)
            print(f"saved {path}", flush=True)

    validation = (env_kwargs(VALIDATION_LAYOUTS), list(range(args.validation_episodes)),
                  args.validate_every)
    try:
        theta, layer_shapes, history = train_es.train(
            None, args.seed, args.hidden, args.popsize, args.train_episodes, args.sigma,
            workers=args.workers, generations=args.generations, backend=args.backend,
            address=args.address, train_env=env_kwargs(TRAIN_LAYOUTS), crowd_humans=HUMANS,
            validation=validation, checkpoint=checkpoint)
    except (ValueError, BackendUnavailable) as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    train_es.to_policy(theta, layer_shapes, crowd_humans=HUMANS).save(args.out)
    print(f"{len(history)} generations in {history[-1]['time'] / 60:.1f} min; saved {args.out}")
    for h in history:
        if "validation" in h:
            print(f"generation {h['generation']:4d}  {h['time'] / 60:5.1f} min  validation "
                  f"success {h['validation']:.3f}  population success {h['success']:.3f}")
    if args.plot is not None:
        plot(history, args.plot, f"CMA-ES on CrowdNav's circle crossing, MLP {args.hidden} "
             f"tanh units, {args.popsize} x {args.train_episodes} episodes per generation, "
             f"seed {args.seed}")


def imitate(args: argparse.Namespace, parser: argparse.ArgumentParser) -> None:
    """``--imitate``: clone the teacher into ``--out`` (examples/crowd_imitation.py)."""
    import json
    import time

    import crowd_imitation
    from pymunk_bot.benchmark.controllers import controller_choice
    from pymunk_bot.config.errors import ScenarioError

    problem = None
    if not 1 <= args.demos <= 100_000 or not 0 <= args.dagger_rounds <= 100:
        problem = "--demos must be in [1, 100000] and --dagger-rounds in [0, 100]"
    elif not 1 <= args.dagger_episodes <= 100_000 or not 1 <= args.epochs <= 10_000:
        problem = "--dagger-episodes must be in [1, 100000] and --epochs in [1, 10000]"
    elif not 1 <= args.hidden <= 1024:
        problem = f"--hidden must be in [1, 1024] with --imitate (got {args.hidden})"
    elif not 1 <= args.workers <= 64:
        problem = f"--workers must be in [1, 64] (got {args.workers})"
    elif (args.demos + args.dagger_rounds * args.dagger_episodes
          > TRAIN_LAYOUTS[1] - TRAIN_LAYOUTS[0]):
        problem = "--demos + --dagger-rounds x --dagger-episodes exceeds the training layouts"
    if problem is None:
        try:
            block = controller_choice(args.imitate).block
        except ScenarioError as exc:  # names --controller: say --imitate
            problem = f"--imitate: {exc.problem}" if exc.source == "--controller" else str(exc)
    if problem is not None:
        print(f"error: {problem}", file=sys.stderr)
        sys.exit(2)
    start = time.time()
    try:
        history = crowd_imitation.imitate(
            block, args.out, HUMANS, [args.hidden], args.seed, args.demos, args.dagger_rounds,
            args.dagger_episodes, args.epochs, args.workers, TRAIN_LAYOUTS,
            list(range(VALIDATION_LAYOUTS[0], VALIDATION_LAYOUTS[0] + args.validation_episodes)))
    except (ValueError, ScenarioError) as exc:  # the teacher's block refused
        print(f"error: --imitate {args.imitate}: {exc}", file=sys.stderr)
        sys.exit(2)
    print(f"saved {args.out}; {(time.time() - start) / 60:.1f} min of wall time, "
          f"{history[-1]['cpu_minutes']:.1f} CPU-minutes")
    print(json.dumps(history))
    if args.plot is not None:
        plot_imitation(history, args.plot, f"Imitation of {block['type']} + DAgger on "
                       f"CrowdNav's circle crossing, MLP {args.hidden} tanh units, seed "
                       f"{args.seed}")


def _axes():
    """A learning-curve figure and its axes (matplotlib headless)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=(7, 4))


def _finish(fig, ax, out: Path, title: str, top: float, legend: str) -> None:
    """ORCA's and the issue's lines, labels and legend; the figure saved to ``out``."""
    import matplotlib.pyplot as plt

    ax.axhline(ORCA_SUCCESS, color="C3", linestyle="--", linewidth=1,
               label=f"crowdnav_orca on the 500 test cases ({ORCA_SUCCESS})")
    ax.axhline(0.9, color="0.5", linestyle=":", linewidth=1, label="the issue's target (0.90)")
    ax.set_ylim(0, top)
    ax.set_ylabel("success without collision")
    ax.legend(loc=legend, fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_imitation(history: list[dict], out: Path, title: str) -> None:
    """Validation success after each fit (round 0: the teacher's demonstrations alone)
    against the CPU time spent so far."""
    fig, ax = _axes()
    ax.plot([h["cpu_minutes"] for h in history], [h["validation"] for h in history], "o-",
            color="C2", label="student, validation episodes (held out)")
    for h in history:
        ax.annotate(f"round {h['round']}", (h["cpu_minutes"], h["validation"]),
                    textcoords="offset points", xytext=(0, -14), fontsize=7, ha="center")
    ax.set_xlabel("CPU minutes (recording, fitting, validating)")
    _finish(fig, ax, out, title, 1.02, "lower right")


def plot(history: list[dict], out: Path, title: str) -> None:
    """Learning curve per generation: the validation success of the mean, and the population's
    success on its training episodes."""
    fig, ax = _axes()
    ax.plot([h["generation"] for h in history], [h["success"] for h in history], color="C0",
            alpha=0.4, label="population, training episodes")
    checked = [h for h in history if "validation" in h]
    ax.plot([h["generation"] for h in checked], [h["validation"] for h in checked], "o-",
            color="C2", label="mean policy, validation episodes (held out)")
    ax.set_xlabel(f"generation ({history[-1]['time'] / 60:.0f} min wall time in all)")
    _finish(fig, ax, out, title, 1.0, "upper left")


if __name__ == "__main__":
    main()
