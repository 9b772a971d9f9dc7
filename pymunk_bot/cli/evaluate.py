"""`pymunk-bot evaluate POLICY SCENARIO --episodes N`: a trained policy's success rate,
contacts and time to goal, with 95 % confidence intervals.

Each episode is the scenario in ``pymunk_bot/Navigation-v0`` (the policy drives its first
robot, or ``--robot``) reset with seed ``--seed + k``; ``--random-goal``, ``--random-start``
and ``--generate KIND`` (of ``--size``, seeds from ``--world-seeds``) draw a new goal, start
pose or generated world per episode (:mod:`pymunk_bot.envs.randomize`). Several kinds
(``--generate office,maze,clutter``), ROS maps (``--maps MAP.yaml ...``: random free starts and
goals on each) or ``--plot PATH`` give one table, a row per family (the same episode seeds in
each), and the plot: contact-free success with its 95 % interval per family. A policy file that
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
    p.add_argument("--generate", type=kind_list, default=None, metavar="KIND[,KIND...]",
                   help="a generated world per episode (the scenario's robot in it): maze, "
                        "clutter or office; several, comma-separated: a table row per kind")
    p.add_argument("--maps", nargs="+", default=None, metavar="MAP_YAML",
                   help="ROS map files: a table row per map, random free starts and goals")
    p.add_argument("--plot", type=Path, default=None, metavar="PATH",
                   help="bar chart of contact-free success per family (.png, .pdf, .svg)")
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


KINDS = ("maze", "clutter", "office")
PLOT_FORMATS = (".png", ".pdf", ".svg")


def kind_list(text: str) -> list[str]:
    """``--generate``: kinds of generated worlds, comma-separated (argparse type)."""
    kinds = [k.strip() for k in text.split(",")]
    bad = [k for k in kinds if k not in KINDS]
    if bad or len(set(kinds)) != len(kinds):
        what = f"'{bad[0]}' is not one" if bad else "a kind is repeated"
        raise argparse.ArgumentTypeError(f"{what}: give {', '.join(KINDS)}, comma-separated "
                                         f"(got '{text}')")
    return kinds


def families(args: argparse.Namespace) -> list[tuple[str, str | None, str | None]]:
    """(row name, kind, map file) of every family the command reports: each kind, then each
    map; one row of the scenario itself (None, None) without either."""
    rows: list[tuple[str, str | None, str | None]] = [
        (kind, kind, None) for kind in (args.generate or [])]
    names = {name for name, _, _ in rows}
    for path in getattr(args, "maps", None) or []:
        name = f"{Path(path).stem} map"
        while name in names:  # two maps of one name: keep the rows apart
            name += "'"
        names.add(name)
        rows.append((name, None, str(path)))
    return rows or [(Path(str(args.scenario)).stem, None, None)]


def env_kwargs(args: argparse.Namespace, kind: str | None = None,
               world_map: str | None = None) -> dict:
    """Navigation-v0's keyword arguments for the command's options: the world of generated
    ``kind`` (default: the first of ``--generate``) or the ROS map file ``world_map`` (with a
    drawn start and goal)."""
    randomize: dict = {}
    if world_map is not None:
        randomize["maps"] = [world_map]
    elif kind is not None or args.generate:
        randomize["generate"] = kind if kind is not None else args.generate[0]
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
    if args.random_start or world_map is not None:
        randomize["start"] = True
    if world_map is not None:  # a map's free space: not the scenario's start or goal
        randomize.pop("size", None)
        randomize.pop("world_seeds", None)
    return {"scenario": args.scenario, "robot": args.robot,
            "random_goal": args.random_goal or world_map is not None,
            "max_episode_time": args.max_time, "control_period": args.control_period,
            "randomize": randomize or None}


def command(args: argparse.Namespace) -> int:
    try:
        from pymunk_bot.envs import NavigationEnv
    except ImportError as exc:
        print(f"error: evaluate: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    from pymunk_bot.envs.evaluation import evaluate_policy, format_summary, outcome_rows, summarize
    from pymunk_bot.envs.families import family_table, plot_families
    from pymunk_bot.policy.files import (
        PolicyFileError, check_runs_on, guidance_for, load_policy, observation_for,
    )

    if args.out is not None:
        check_output("--out", args.out, (".csv",))
    try:
        policy = load_policy(args.policy)
    except PolicyFileError as exc:
        print(f"error: {args.policy}: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.plot is not None:
        check_output("--plot", args.plot, PLOT_FORMATS)
    rows = families(args)
    table = len(rows) > 1 or bool(args.maps) or args.plot is not None
    try:  # a policy trained with plan guidance records it: it is evaluated with it
        guidance = guidance_for(policy, True if args.plan_guidance else None)
    except PolicyFileError as exc:
        print(f"error: {args.policy}: {exc} (--plan-guidance)", file=sys.stderr)
        return EXIT_BAD_INPUT
    # a policy trained on the crowd_state observation records it: it is evaluated on it
    observation = observation_for(policy, None)
    runs = []
    for _, kind, world_map in rows:
        kwargs = env_kwargs(args, kind, world_map)
        kwargs["plan_guidance"] = guidance
        kwargs["observation"] = observation
        try:
            env = NavigationEnv(**kwargs)
        except ValueError as exc:  # a bad option value (ScenarioError is raised as it is)
            print(f"error: evaluate: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        except ScenarioError as exc:
            if world_map is None:
                raise
            print(f"error: --maps: {exc.problem}", file=sys.stderr)
            return EXIT_BAD_INPUT
        inputs, outputs = env.episode.task.obs_size, env.episode.task.action_size
        env.close()
        if policy.inputs not in (None, inputs) or policy.outputs not in (None, outputs):
            print(f"error: {args.policy}: takes {policy.inputs} inputs and gives "
                  f"{policy.outputs} outputs; robot '{env.episode.robot_name}' of "
                  f"{args.scenario} gives {inputs} and takes {outputs} (was it trained with "
                  "another LiDAR or drive?)", file=sys.stderr)
            return EXIT_BAD_INPUT
        runs.append(kwargs)
    results = []
    for (name, _, _), kwargs in zip(rows, runs):
        try:
            check_runs_on(policy, inputs, outputs)
            results.append((name, evaluate_policy(args.policy, kwargs, args.episodes, args.seed,
                                                  args.workers)))
        except PolicyFileError as exc:
            print(f"error: {args.policy}: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
    summaries = [(name, summarize(outcomes)) for name, outcomes in results]
    if not table:
        summary = summaries[0][1]
        print(json.dumps(summary, indent=2) if args.json else format_summary(summary))
    elif args.json:
        print(json.dumps({"families": dict(summaries)}, indent=2))
    else:
        print(family_table(summaries))
    if args.plot is not None:
        plot_families(summaries, args.plot, f"{args.policy.name}: {args.episodes} episodes "
                                            f"per family, seeds {args.seed}+")
    if args.out is not None:
        from pymunk_bot.outcomes.results import write_atomic

        text = io.StringIO()
        lines = [({"family": name} if table else {}) | row
                 for name, outcomes in results for row in outcome_rows(outcomes)]
        writer = csv.DictWriter(text, fieldnames=list(lines[0]))
        writer.writeheader()
        writer.writerows(lines)
        write_atomic(args.out, text.getvalue().encode("utf-8"))
    return EXIT_OK
