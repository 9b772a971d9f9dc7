"""Crowd scenarios drawn per episode (``randomize={"crowd": SUITE}``, see :mod:`.randomize`):
one of a benchmark suite's scenarios, its CrowdNav layout drawn from a seed, with the env's
learning robot put at the layout's start with the layout's goal."""
from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from pymunk_bot.config.errors import ScenarioError

WORLD_PLACE = ("size", "map", "map_scale")  # the keys of a world section that say where it is


def crowd_suite(spec: Any, generate: str | None, source: str) -> tuple[Any, ...]:
    """The entries (:class:`~pymunk_bot.benchmark.suite.Entry`) of the suite ``spec`` names:
    a shipped suite's name, a generator spec or a folder of scenarios. ScenarioError naming
    ``randomize.crowd`` if it is none of them."""
    from pymunk_bot.benchmark.suite import load_suite

    where = "randomize.crowd"
    if generate is not None:
        raise ScenarioError(source, where, "draws the world itself: leave out "
                                           "randomize.generate")
    if not isinstance(spec, str) or not spec:
        raise ScenarioError(source, where, f"must name a suite: a shipped suite (see `pymunk-bot"
                                           f" benchmark --list`), a spec or a folder (got "
                                           f"{spec!r:.60})")
    try:
        return tuple(load_suite(spec))
    except ScenarioError as exc:
        raise ScenarioError(source, where, str(exc)) from None


def crowd_world(base: dict, robot: str, entry: Any, seed: int, source: str) -> dict:
    """``base`` (scenario data) with the world, obstacles and pedestrians of ``entry``'s
    episode of ``seed``, its learning robot ``robot`` at that episode's start with its goal
    (other robots, ``expect`` and ``events`` left out)."""
    from pymunk_bot.benchmark.suite import episode_data

    try:
        drawn = episode_data(entry, seed)
    except ScenarioError as exc:
        raise ScenarioError(source, "randomize.crowd", str(exc)) from None
    data = copy.deepcopy(base)
    learner = next(r for r in data["robots"] if r["name"] == robot)
    placed = drawn["robots"][0]
    learner["pose"] = list(placed["pose"])
    goal = (placed.get("goal") or {}).get("position")
    if goal is not None:
        learner["goal"] = {**(learner.get("goal") or {}), "position": list(goal)}
    data["robots"] = [learner]
    world = {k: v for k, v in data["world"].items() if k not in WORLD_PLACE}
    world.update({k: v for k, v in drawn["world"].items() if k in WORLD_PLACE})
    if "map" in world and not Path(world["map"]).is_absolute():  # a scenario file's own map
        world["map"] = str(Path(entry.base_dir) / world["map"])
    data["world"] = world
    data["obstacles"] = copy.deepcopy(drawn["obstacles"])
    data.pop("expect", None)
    data.pop("events", None)
    return data
