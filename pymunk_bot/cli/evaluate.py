"""`pymunk-bot evaluate POLICY SCENARIO --episodes N`: a trained policy's success rate,
contacts and time to goal, with 95 % confidence intervals.

Each episode is the scenario in ``pymunk_bot/Navigation-v0`` (the policy drives its first
robot, or ``--robot``) reset with seed ``--seed + k``; ``--random-goal``, ``--random-start``
and ``--generate KIND`` (of ``--size``, seeds from ``--world-seeds``) draw a new goal, start
pose or generated world per episode (:mod:`pymunk_bot.envs.randomize`). A policy file that
records plan guidance (docs/learning.md) is evaluated with it; ``--plan-guidance`` turns it on
for a file that does not record it (an ONNX model). Exit status: 0 evaluated, 2 bad input (a
policy file that cannot be read, does not fit the robot, returns a NaN action, or was trained
without plan guidance and is given ``--plan-guidance``).
"""
from __future__ import annotations

import argparse
import csv
import io
import json
import sys
from pathlib import Path

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.cli.arguments import (
    EXIT_BAD_INPUT, EXIT_OK, check_output, count_up_to, duration_seconds, jobs_count, seed_number,
)

MAX_EPISODES = 100_000


def add_parser(sub) -> None:
    p = sub.add_parser("evaluate", help="success rate, contacts and time to goal of a trained "
                                        "policy (.npz or .onnx) over many episodes")
    p.add_argument("policy", type=Path, help="the policy file (.npz MLP or .onnx)")
    p.add_argument("scenario", help="scenario file or shipped name")
    p.add_argument("--episodes", type=count_up_to(MAX_EPISODES), default=100, help="episodes (default 100)")
    p.add_argument("--seed", type=seed_number, default=0, help="episode k is reset with seed+k")
    p.add_argument("--robot", default=None, help="the robot the policy drives (default: first)")
    p.add_argument("--random-goal", action="store_true", help="a random free goal per episode")
    p.add_argument("--random-start", action="store_true", help="a random free start per episode")
    p.add_argument("--generate", choices=("maze", "clutter", "office"), default=None,
                   help="a generated world per episode (the scenario's robot in it)")
    p.add_argument("--world-seeds", default=None, metavar="LOW:HIGH",
                   help="generated worlds' seeds are drawn from [LOW, HIGH)")
    p.add_argument("--size", type=float, nargs=2, default=None, metavar=("WIDTH", "HEIGHT"),
                   help="generated worlds' arena [m] (default: the kind's own)")
    p.add_argument("--max-time", type=duration_seconds, default=None,
                   help="episode time limit [s] (default: the scenario's world.duration)")
    p.add_argument("--control-period", type=duration_seconds, default=0.1,
                   help="seconds per action (the policy controller's 1 / rate), default 0.1")
    p.add_argument("--plan-guidance", action="store_true",
                   help="goal features along an A* path (default: as the policy file records)")
    p.add_argument("--workers", type=jobs_count, default=1, help="processes (default 1)")
    p.add_argument("--out", type=Path, default=None, help="one row per episode (.csv)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=command)


def env_kwargs(args: argparse.Namespace) -> dict:
    """Navigation-v0's keyword arguments for the command's options."""
    randomize: dict = {}
    if args.generate is not None:
        randomize["generate"] = args.generate
    for option, value in (("--world-seeds", args.world_seeds), ("--size", args.size)):
        if value is not None and args.generate is None:
            raise ScenarioError(option, "", "applies to generated worlds: add --generate KIND")
    if args.size is not None:
        randomize["size"] = list(args.size)
    if args.world_seeds is not None:
        low, _, high = args.world_seeds.partition(":")
        try:
            randomize["world_seeds"] = [int(low), int(high)]
        except ValueError:
            raise ScenarioError("--world-seeds", "", f"must be LOW:HIGH, whole numbers "
                                                     f"(got '{args.world_seeds}')") from None
    if args.random_start:
        randomize["start"] = True
    return {"scenario": args.scenario, "robot": args.robot, "random_goal": args.random_goal,
            "max_episode_time": args.max_time, "control_period": args.control_period,
            "randomize": randomize or None}


def command(args: argparse.Namespace) -> int:
    try:
        from pymunk_bot.envs import NavigationEnv
    except ImportError as exc:
        print(f"error: evaluate: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    from pymunk_bot.envs.evaluation import evaluate_policy, format_summary, outcome_rows, summarize
    from pymunk_bot.policy.files import PolicyFileError, check_runs_on, guidance_for, load_policy

    if args.out is not None:
        check_output("--out", args.out, (".csv",))
    try:
        policy = load_policy(args.policy)
    except PolicyFileError as exc:
        print(f"error: {args.policy}: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    kwargs = env_kwargs(args)
    try:  # a policy trained with plan guidance records it: it is evaluated with it
        kwargs["plan_guidance"] = guidance_for(policy, True if args.plan_guidance else None)
    except PolicyFileError as exc:
        print(f"error: {args.policy}: {exc} (--plan-guidance)", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        env = NavigationEnv(**kwargs)
    except ValueError as exc:  # a bad option value (ScenarioError is raised as it is)
        print(f"error: evaluate: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    inputs, outputs = env.episode.task.obs_size, env.episode.task.action_size
    env.close()
    if policy.inputs not in (None, inputs) or policy.outputs not in (None, outputs):
        print(f"error: {args.policy}: takes {policy.inputs} inputs and gives {policy.outputs} "
              f"outputs; robot '{env.episode.robot_name}' of {args.scenario} gives {inputs} "
              f"and takes {outputs} (was it trained with another LiDAR or drive?)",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        check_runs_on(policy, inputs, outputs)
        outcomes = evaluate_policy(args.policy, kwargs, args.episodes, args.seed, args.workers)
    except PolicyFileError as exc:
        print(f"error: {args.policy}: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    summary = summarize(outcomes)
    print(json.dumps(summary, indent=2) if args.json else format_summary(summary))
    if args.out is not None:
        from pymunk_bot.outcomes.results import write_atomic

        text = io.StringIO()
        rows = outcome_rows(outcomes)
        writer = csv.DictWriter(text, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
        write_atomic(args.out, text.getvalue().encode("utf-8"))
    return EXIT_OK
