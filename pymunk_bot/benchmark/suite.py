"""Suites: which scenarios a benchmark runs.

A suite is a scenario file, a folder of them, a generator spec (a YAML file with ``layouts:``:
crowd layouts over static worlds at several densities, drawn anew for every seed), or the name
of a shipped suite (``scenarios/benchmark/<name>.yaml``, listed by ``pymunk-bot benchmark
--list``). Each scenario of a suite is an :class:`Entry`; :func:`episode_data` gives the
scenario data of one episode.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import Field, ValidationError

from pymunk_bot.config.loader import shipped_scenario_dirs
from pymunk_bot.config.types import Duration, Name, PositiveFloat, PositiveInt, Section, Vec2
from pymunk_bot.config.yaml_source import parse_yaml, read_text
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.benchmark.crowdnav import CROWDNAV_LAYOUTS, SQUARE_WIDTH, CrowdNavLayoutError, \
    circle_crossing, square_crossing
from pymunk_bot.benchmark.layouts import LAYOUTS, LayoutError, draw_layout

MAX_ENTRIES = 10_000  # scenarios per suite at most
MAX_HUMANS = 500  # pedestrians per generated scenario at most


@dataclass(frozen=True)
class Entry:
    """One scenario of a suite: a file's data, or a generated layout's recipe."""

    suite: str
    scenario: str
    source: str  # names it in messages: the file, or "spec.yaml [world-layout-density]"
    base_dir: str  # where a relative map or a user's controller module is looked for
    data: dict = field(hash=False)  # a file's scenario data, or the recipe (generated)
    generated: bool = False


class WorldSpec(Section):
    """A static world of a generator spec: ``size`` (open), ``generate`` (a generated clutter,
    maze or office world), or ``map`` (a ROS map or SVG plan, relative to the spec)."""

    size: Vec2 | None = None
    generate: str | None = None
    seed: Annotated[int, Field(ge=0)] = 0
    map: str | None = None
    map_scale: PositiveFloat | None = None
    obstacles: list[dict] = []


class GeneratorSpec(Section):
    """A generated suite: every layout over every world at every density."""

    suite: Name
    description: str = ""
    duration: Duration = 30.0  # [s] per episode
    stage: Annotated[PositiveFloat, Field(ge=3.0, le=100.0)] = 8.0  # [m] side of the layout
    robot: dict  # the robot (pose and goal position are drawn)
    pedestrian: dict = {}  # keys every pedestrian gets (policy, react_to_robot, radius, ...)
    worlds: dict[Name, WorldSpec] = Field(min_length=1)
    layouts: list[str] = Field(min_length=1)
    densities: dict[Name, Annotated[PositiveInt, Field(le=MAX_HUMANS)]] = Field(min_length=1)
    # [m] the circle of CrowdNav's layouts (the robot crosses it; crowdnav_circle_crossing's
    # humans start on it), centred in the world
    circle_radius: Annotated[PositiveFloat, Field(le=50.0)] = 4.0
    # [m] the side of crowdnav_square_crossing's square, centred in the world
    square_width: Annotated[PositiveFloat, Field(le=100.0)] = SQUARE_WIDTH
    # true: an episode ends at the robot's first collision (CrowdNav's protocol); false: it
    # goes on to the goal or the duration, and later arrivals count as reached
    end_at_collision: bool = False


def shipped_suites() -> dict[str, Path]:
    """Name -> spec of every shipped suite."""
    found: dict[str, Path] = {}
    for d in shipped_scenario_dirs():
        for path in sorted((d / "benchmark").glob("*.yaml")):
            found.setdefault(path.stem, path)
    return found


def _read(path: Path) -> Any:
    """The file's data, read as scenario files are: a regular file of bounded size (never a
    pipe or a device), UTF-8, bounded YAML."""
    data, _ = parse_yaml(read_text(path, str(path)), str(path))
    return data


def _spec(path: Path, data: dict) -> GeneratorSpec:
    try:
        spec = GeneratorSpec.model_validate(data)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise ScenarioError(str(path), where, first["msg"]) from None
    known = LAYOUTS + CROWDNAV_LAYOUTS
    for i, name in enumerate(spec.layouts):
        if name not in known:
            raise ScenarioError(str(path), f"layouts[{i}]", f"unknown layout '{name}' "
                                                          f"(choose from {', '.join(known)})")
        if name in CROWDNAV_LAYOUTS:
            for world_name, world in spec.worlds.items():
                if world.size is None or world.generate or world.map or world.obstacles:
                    raise ScenarioError(str(path), f"worlds.{world_name}",
                                        f"layout {name} needs an open world (size only)")
                # [m] the circle (and the square) and 2 m beyond
                least = max(2 * spec.circle_radius, spec.square_width
                            if name == "crowdnav_square_crossing" else 0.0) + 4.0
                if min(world.size) < least:
                    raise ScenarioError(str(path), f"worlds.{world_name}.size",
                                        f"layout {name} needs at least {least:g} m each way "
                                        "(its circle or square and 2 m beyond it)")
    for name, world in spec.worlds.items():
        if (world.generate is not None) + (world.map is not None) + (
                world.size is not None and world.generate is None) != 1:
            raise ScenarioError(str(path), f"worlds.{name}", "give one of size (an open room), "
                                "generate (with an optional size) or map")
    return spec


def _generated(path: Path, spec: GeneratorSpec) -> list[Entry]:
    folder = path.resolve().parent
    out = []
    for world_name, world in spec.worlds.items():
        for layout in spec.layouts:
            for density, humans in spec.densities.items():
                scenario = f"{world_name}-{layout}-{density}"
                recipe = {"spec": spec.model_dump(), "world": world_name, "layout": layout,
                          "humans": humans, "folder": str(folder)}
                out.append(Entry(spec.suite, scenario, f"{path} [{scenario}]", str(folder),
                                 recipe, generated=True))
    return out


def _entries_of_file(path: Path, suite: str) -> list[Entry]:
    data = _read(path)
    if not isinstance(data, dict):
        raise ScenarioError(str(path), "", "must be a YAML mapping (a scenario or a suite spec)")
    if "layouts" in data:
        return _generated(path, _spec(path, data))
    name = str(data.get("name", path.stem))
    return [Entry(suite, name, str(path), str(path.resolve().parent), data)]


def load_suite(spec: str) -> list[Entry]:
    """The scenarios of a suite named by ``spec`` (file, folder or shipped name)."""
    path = Path(spec)
    if not path.exists():
        shipped = shipped_suites()
        if spec not in shipped:
            from pymunk_bot.config.messages import did_you_mean
            raise ScenarioError(spec, "", "no such file, folder or shipped suite"
                                f"{did_you_mean(spec, list(shipped))}; see `pymunk-bot "
                                "benchmark --list`")
        path = shipped[spec]
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.suffix in (".yaml", ".yml"))
        entries = [e for f in files for e in _entries_of_file(f, path.name)]
    else:
        entries = _entries_of_file(path, path.stem)
    if not entries:
        raise ScenarioError(str(path), "", "the suite has no scenarios (no .yaml files)")
    if len(entries) > MAX_ENTRIES:
        raise ScenarioError(str(path), "", f"more than {MAX_ENTRIES} scenarios")
    return entries


@functools.lru_cache(maxsize=16)
def _map_geometry(path: str, scale: float | None) -> Any:
    from pymunk_bot.maps.files import load_world_map
    return load_world_map(path, scale, source=path)


def episode_data(entry: Entry, seed: int, duration: float | None = None) -> dict:
    """The scenario data of ``entry``'s episode with ``seed`` (a generated layout is drawn
    from the seed); ``duration`` [s] replaces the world's."""
    if not entry.generated:
        data = dict(entry.data)
        data["seed"] = seed
    else:
        data = _generate(entry, seed)
    if duration is not None:
        data["world"] = dict(data["world"], duration=float(duration))
    return data


def _generate(entry: Entry, seed: int) -> dict:
    recipe = entry.data
    spec = GeneratorSpec.model_validate(recipe["spec"])
    world = spec.worlds[recipe["world"]]
    geometry = None
    obstacles = [dict(o) for o in world.obstacles]
    if world.generate is not None:
        from pymunk_bot.maps.generate import generate
        made = generate(world.generate, world.seed, None if world.size is None
                        else (float(world.size[0]), float(world.size[1])))
        section: dict[str, Any] = {"size": made["world"]["size"]}
        obstacles += made["obstacles"]
    elif world.map is not None:
        path = (Path(recipe["folder"]) / world.map).resolve()
        section = {"map": str(path)}
        if world.map_scale is not None:
            section["map_scale"] = world.map_scale
        geometry = _map_geometry(str(path), world.map_scale)
    else:
        assert world.size is not None
        section = {"size": [float(world.size[0]), float(world.size[1])]}
    robot = dict(spec.robot)
    robot.setdefault("name", "r1")
    if recipe["layout"] in CROWDNAV_LAYOUTS:
        placed_obstacles, placed_robot = _crowdnav(entry, spec, recipe["layout"], section, robot,
                                                   recipe["humans"], seed)
        return _episode(entry, spec, recipe, seed, section, placed_obstacles, placed_robot)
    try:
        placed_obstacles, placed_robot = draw_layout(
            recipe["layout"], section, obstacles, robot, recipe["humans"], spec.pedestrian,
            spec.stage, seed, geometry)
    except LayoutError as exc:
        raise ScenarioError(entry.source, "", str(exc)) from None
    return _episode(entry, spec, recipe, seed, section, placed_obstacles, placed_robot)


def _crowdnav(entry: Entry, spec: GeneratorSpec, layout: str, section: dict, robot: dict,
              humans: int, seed: int) -> tuple[list[dict], dict]:
    """CrowdNav's test case ``seed`` of ``layout`` (benchmark/crowdnav.py), its frame's origin
    at the world's centre."""
    centre = np.array(section["size"], dtype=float) / 2
    pedestrian = dict(spec.pedestrian)
    robot_radius = float(robot.get("radius", 0.2))
    human_radius = float(pedestrian.get("radius", 0.25))
    try:
        if layout == "crowdnav_square_crossing":
            start, goal, routes = square_crossing(seed, humans, spec.circle_radius,
                                                  spec.square_width, robot_radius, human_radius)
        else:
            start, goal, routes = circle_crossing(seed, humans, spec.circle_radius, robot_radius,
                                                  human_radius,
                                                  float(pedestrian.get("speed", 1.3)))
    except CrowdNavLayoutError as exc:
        raise ScenarioError(entry.source, "", str(exc)) from None
    walkers = [dict(pedestrian, type="pedestrian", center=(centre + a).tolist(),
                    goals=[(centre + b).tolist()], mode="once") for a, b in routes]
    heading = math.atan2(goal[1] - start[1], goal[0] - start[0])
    placed = dict(robot, pose=[*(centre + start).tolist(), heading])
    placed["goal"] = dict(robot.get("goal", {}), position=(centre + goal).tolist())
    return walkers, placed


def end_at_collision(entry: Entry) -> bool:
    """Whether ``entry``'s episodes end at the robot's first collision (a suite option)."""
    return bool(entry.generated and entry.data["spec"].get("end_at_collision", False))


def _episode(entry: Entry, spec: GeneratorSpec, recipe: dict, seed: int, section: dict,
             placed_obstacles: list[dict], placed_robot: dict) -> dict:
    return {"name": entry.scenario.replace("-", "_"), "seed": seed,
            "description": f"{recipe['layout']} with {recipe['humans']} pedestrians in the "
                           f"{recipe['world']} world (suite {spec.suite}, seed {seed})",
            "world": dict(section, duration=spec.duration),
            "obstacles": placed_obstacles, "robots": [placed_robot]}
