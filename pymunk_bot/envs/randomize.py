"""Domain randomization: a new scenario drawn for every episode (``randomize=`` of the envs).

    gym.make("pymunk_bot/Navigation-v0", random_goal=True, randomize={
        "generate": "clutter",             # a generated world per episode (maze | clutter | office)
                                           # or a list of kinds, one drawn per episode
        "maps": ["scenarios/maps/office.yaml"],  # ROS maps (.yaml): drawn among the kinds
        "world_seeds": [0, 1000],          # its seed drawn from [0, 1000) (default [0, 2**31-1))
        "size": [8.0, 6.0],                # of the generated arena [m] (default: the kind's)
        "start": True,                     # a random free start pose
        "set": {"robots[0].max_wheel_speed": [0.5, 1.0],        # a range: uniform draw
                "robots[0].lidar.noise_std": {"choices": [0.0, 0.02]}},
    })
    gym.make("pymunk_bot/Navigation-v0", scenario=..., randomize={"crowd": "crowds"})

``crowd`` names a benchmark suite (a shipped suite's name, a generator spec or a folder of
scenarios, as ``pymunk-bot benchmark`` takes it): each episode draws one of its scenarios and,
for a generated one, its CrowdNav layout (stage, pedestrians' starts and routes, the robot's
start and goal) from a seed drawn from the episode's generator, as the benchmark's episode of
that seed (:func:`pymunk_bot.benchmark.suite.episode_data`).

``generate`` may list kinds (``["clutter", "office", "maze"]``) and ``maps`` lists ROS map
files (a path, or one relative to a shipped scenarios folder: ``maps/office.yaml``): each
episode draws one of these families uniformly (kinds first, then maps, in the order given), then
a world of it. A map world is the map file's walls with no other obstacle: it needs
``start: true`` and the env's ``random_goal`` (a free start and goal are drawn on it). One kind
and no maps draws no family (the draws of one ``generate: KIND`` are unchanged).

``set`` takes the key paths of ``sweep --set`` and is checked the same way: each range's ends
and each choice must give a valid scenario. A range of two integers draws integers (both ends
included). A generated world or a suite's scenario keeps the scenario's learning robot (drive,
size, sensors) and takes the world's arena (or map), obstacles, start and goal; other robots
are left out. Every draw comes from the episode's generator: a seed gives the same episodes.
"""
from __future__ import annotations

import copy
import functools
import math
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from pymunk_bot.config import parse_scenario
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.maps.generate import KINDS, generate
from pymunk_bot.sweep.grid import apply_override, parse_key_path
from pymunk_bot.envs.crowd_draw import crowd_suite, crowd_world

KEYS = ("generate", "maps", "world_seeds", "size", "start", "set", "crowd")
MAX_FAMILIES = 64  # kinds and maps listed at most
MAX_CHOICES = 1000
MAX_SEED = 2**31 - 1
WORLD_CACHE = 256  # generated worlds kept (drawing one runs a solvability check)
START_TRIES = 200  # random start poses tried before giving up on a crowded world
START_CLEARANCE = 0.15  # [m] free space around a random start, beyond the robot's radius
START_GOAL_GAP = 1.0  # [m] a random start at least this far from the goal


@dataclass(frozen=True)
class Draw:
    """How one scenario key is drawn: uniformly from [low, high] or from ``choices``."""

    path: str
    low: float | None = None
    high: float | None = None
    choices: tuple[Any, ...] = ()
    integer: bool = False

    def values(self) -> list[Any]:
        """The values that bound what a draw gives (each is checked against the scenario)."""
        return list(self.choices) if self.choices else [self.low, self.high]

    def sample(self, rng: np.random.Generator) -> Any:
        """One draw from ``rng``."""
        if self.choices:
            return copy.deepcopy(self.choices[int(rng.integers(len(self.choices)))])
        assert self.low is not None and self.high is not None
        if self.integer:
            return int(rng.integers(int(self.low), int(self.high) + 1))
        return float(rng.uniform(self.low, self.high))


@dataclass(frozen=True)
class Randomization:
    """What is drawn anew every episode (see the module docstring)."""

    generate: str | None = None  # the first kind (None: no generated world)
    kinds: tuple[str, ...] = ()  # every kind drawn from
    maps: tuple[str, ...] = ()  # [resolved paths] of ROS map files drawn from
    world_seeds: tuple[int, int] = (0, MAX_SEED)
    size: tuple[float, float] | None = None  # [m]
    start: bool = False
    draws: tuple[Draw, ...] = ()
    crowd: str | None = None  # a benchmark suite whose scenarios are drawn
    _worlds: OrderedDict = field(default_factory=OrderedDict, compare=False, repr=False)
    _suite: tuple = field(default=(), compare=False, repr=False)  # its entries

    @classmethod
    def parse(cls, value: Mapping[str, Any], source: str) -> "Randomization":
        """From the ``randomize`` mapping; ScenarioError naming ``randomize.<key>`` if bad."""
        if not isinstance(value, Mapping):
            raise ScenarioError(source, "randomize", f"must be a mapping (got {value!r:.60})")
        unknown = sorted(set(value) - set(KEYS))
        if unknown:
            raise ScenarioError(source, f"randomize.{unknown[0]}",
                                f"unknown key; valid: {', '.join(KEYS)}")
        kinds = _kinds(value.get("generate"), source)
        kind = kinds[0] if kinds else None
        maps = _maps(value.get("maps"), source)
        if maps and not value.get("start", False):
            raise ScenarioError(source, "randomize.maps", "a map world needs a drawn start: "
                                                          "add randomize.start: true")
        if maps and value.get("crowd") is not None:
            raise ScenarioError(source, "randomize.crowd", "draws the world itself: leave out "
                                                           "randomize.maps")
        seeds = value.get("world_seeds", (0, MAX_SEED))
        if not (isinstance(seeds, (list, tuple)) and len(seeds) == 2
                and all(isinstance(s, int) and not isinstance(s, bool) for s in seeds)
                and 0 <= seeds[0] < seeds[1] <= MAX_SEED):
            raise ScenarioError(source, "randomize.world_seeds", "must be [low, high) with "
                                f"0 <= low < high <= {MAX_SEED} (got {seeds!r:.60})")
        size = value.get("size")
        if size is not None and not (isinstance(size, (list, tuple)) and len(size) == 2 and all(
                isinstance(s, (int, float)) and math.isfinite(s) for s in size)):
            raise ScenarioError(source, "randomize.size", f"must be [width, height] in metres "
                                                          f"(got {size!r:.60})")
        start = value.get("start", False)
        if not isinstance(start, bool):
            raise ScenarioError(source, "randomize.start", f"must be true or false (got {start!r})")
        keys = value.get("set") or {}
        if not isinstance(keys, Mapping):
            raise ScenarioError(source, "randomize.set", "must map key paths to [low, high] "
                                                         "or {choices: [...]}")
        draws = tuple(_draw(path, spec, source) for path, spec in keys.items())
        crowd = value.get("crowd")
        entries: tuple = ()
        if crowd is not None:
            entries = crowd_suite(crowd, kind, source)
        return cls(kind, kinds, maps, (int(seeds[0]), int(seeds[1])),
                   None if size is None else (float(size[0]), float(size[1])), start, draws,
                   None if crowd is None else str(crowd), _suite=entries)

    @property
    def changes_world(self) -> bool:
        """Whether an episode's scenario differs from the next one's in more than its seed."""
        return (self.generate is not None or bool(self.maps) or self.crowd is not None
                or self.start or bool(self.draws))

    @property
    def families(self) -> tuple[str, ...]:
        """The kinds of generated worlds, then the map files, drawn from (uniformly)."""
        return self.kinds + self.maps

    def check(self, base: dict, robot: str, source: str) -> None:
        """Every range end and choice, applied to ``base`` (or a generated world), parses:
        a ScenarioError naming the key otherwise, before any episode runs."""
        if self._suite:  # the suite's first scenario, drawn from seed 0
            world = crowd_world(base, robot, self._suite[0], 0, source)
            try:
                parse_scenario(world, source)
            except ScenarioError as exc:
                raise ScenarioError(source, "randomize.crowd",
                                    f"{exc.source}: {exc.path}: {exc.problem}") from None
        else:
            for family in self.families[1:]:  # the first is checked with the draws below
                parse_scenario(self.world(base, robot, self.world_seeds[0], source, family),
                               source)
            world = self.world(base, robot, self.world_seeds[0], source)
        for draw in self.draws:
            for value in draw.values():
                data = copy.deepcopy(world)
                _apply(data, draw.path, value, source)
                try:
                    parse_scenario(data, source)
                except ScenarioError as exc:
                    raise ScenarioError(source, f"randomize.set.{draw.path}",
                                        f"{value!r}: {exc.path}: {exc.problem}") from None

    def scenario(self, base: dict, robot: str, rng: np.random.Generator, source: str) -> dict:
        """One episode's scenario data (before the start pose, see :meth:`start_pose`)."""
        if self._suite:  # one of the suite's scenarios, and its layout's seed
            entry = self._suite[int(rng.integers(len(self._suite)))]
            # its layout's seed from world_seeds (rng.integers(0, MAX_SEED) by default: the
            # same draw as integers(MAX_SEED)); a trainer keeps clear of the test cases' seeds
            data = crowd_world(base, robot, entry, int(rng.integers(*self.world_seeds)), source)
        else:
            families = self.families
            family = families[int(rng.integers(len(families)))] if len(families) > 1 else None
            if family in self.maps:
                seed = 0
            else:
                seed = int(rng.integers(*self.world_seeds)) if self.generate is not None else 0
            data = copy.deepcopy(self.world(base, robot, seed, source, family))
        for draw in self.draws:
            _apply(data, draw.path, draw.sample(rng), source)
        return data

    def world(self, base: dict, robot: str, seed: int, source: str,
              family: str | None = None) -> dict:
        """``base`` with the world of ``family`` (a kind or a map file; default: the first
        family) in it, a generated one of ``seed``; ``base`` itself with no family."""
        family = family if family is not None else (self.families or (None,))[0]
        if family is None:
            return base
        if family in self.maps:
            return map_world(base, robot, family)
        world = self._worlds.get((family, seed))
        if world is None:
            world = generate(family, seed, self.size)
            self._worlds[(family, seed)] = world
            if len(self._worlds) > WORLD_CACHE:
                self._worlds.popitem(last=False)
        data = copy.deepcopy(base)
        learner = next(r for r in data["robots"] if r["name"] == robot)
        made = world["robots"][0]
        learner["pose"] = list(made["pose"])
        learner["goal"] = {**(learner.get("goal") or {}), "position": list(made["goal"]["position"])}
        data["robots"] = [learner]
        data["world"] = {**{k: v for k, v in data["world"].items() if k not in ("map", "map_scale")},
                         "size": list(world["world"]["size"])}
        data["obstacles"] = copy.deepcopy(world["obstacles"])
        data.pop("expect", None)
        data.pop("events", None)
        return data


def map_world(base: dict, robot: str, path: str) -> dict:
    """``base`` in the world of the ROS map file ``path``: its walls and nothing else, the
    learning robot alone (its start and goal are drawn on the map)."""
    data = copy.deepcopy(base)
    learner = next(r for r in data["robots"] if r["name"] == robot)
    spot = list(roomiest_spot(path))  # a valid pose and goal until the episode draws its own
    learner["pose"] = spot + [0.0]
    learner["goal"] = {**(learner.get("goal") or {}), "position": spot}
    data["robots"] = [learner]
    data["world"] = {**{k: v for k, v in data["world"].items()
                        if k not in ("size", "map", "map_scale")}, "map": path}
    data["obstacles"] = []
    for key in ("expect", "events", "pedestrians"):
        data.pop(key, None)
    return data


@functools.lru_cache(maxsize=64)
def roomiest_spot(path: str) -> tuple[float, float]:
    """The centre [m] of the free cell of the ROS map ``path`` farthest from its solid."""
    from scipy.ndimage import distance_transform_edt

    from pymunk_bot.maps.outlines import solid_cells
    from pymunk_bot.maps.ros import read_ros_map

    grid = read_ros_map(path)
    room = distance_transform_edt(np.pad(~solid_cells(grid), 1))  # the edge is solid too
    row, col = np.unravel_index(int(np.argmax(room)), room.shape)
    row, col = row - 1, col - 1  # without the padding
    return (grid.origin[0] + (col + 0.5) * grid.resolution,
            grid.origin[1] + (row + 0.5) * grid.resolution)


def start_pose(sim, robot, rng: np.random.Generator) -> tuple[float, float, float]:
    """A free pose for ``robot`` in ``sim``'s world: clear of everything but the robot itself by
    START_CLEARANCE, START_GOAL_GAP from its goal, heading uniform."""
    import pymunk

    world, body = sim.world, robot.body
    clearance = robot.radius + START_CLEARANCE  # [m]
    goal = robot.goal
    everything = pymunk.ShapeFilter()
    for _ in range(START_TRIES):
        x, y = world.random_point(rng, clearance)
        theta = float(rng.uniform(-math.pi, math.pi))
        if goal is not None and math.hypot(x - goal[0], y - goal[1]) < START_GOAL_GAP:
            continue
        if world.map is not None and world.map.is_solid(x, y):  # inside a map's solid
            continue
        hits = world.space.point_query((x, y), clearance, everything)
        if all(hit.shape is not None and hit.shape.body is body for hit in hits):
            return x, y, theta
    raise ScenarioError(sim.source, "randomize.start", f"no free start pose found in "
                        f"{START_TRIES} tries: no open space {clearance:g} m clear of everything")


def _apply(data: dict, path: str, value: Any, source: str) -> None:
    try:
        apply_override(data, path, value)
    except KeyError as exc:
        where, problem = exc.args
        raise ScenarioError(source, f"randomize.set.{where}", problem) from None


def _draw(path: Any, spec: Any, source: str) -> Draw:
    where = f"randomize.set.{path}"
    try:
        parse_key_path(str(path))
    except ValueError as exc:
        raise ScenarioError(source, where, str(exc)) from None
    if isinstance(spec, Mapping):
        choices = spec.get("choices")
        if set(spec) != {"choices"} or not isinstance(choices, (list, tuple)) or not (
                0 < len(choices) <= MAX_CHOICES):
            raise ScenarioError(source, where, f"{{choices: [...]}} takes 1 to {MAX_CHOICES} "
                                               f"values (got {spec!r:.60})")
        return Draw(str(path), choices=tuple(choices))
    numbers = isinstance(spec, (list, tuple)) and len(spec) == 2 and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in spec)
    if not numbers or spec[0] > spec[1]:
        raise ScenarioError(source, where, f"must be [low, high] (low <= high) or "
                                           f"{{choices: [...]}} (got {spec!r:.60})")
    integer = all(isinstance(v, int) for v in spec)
    return Draw(str(path), float(spec[0]), float(spec[1]), integer=integer)


def _kinds(value: Any, source: str) -> tuple[str, ...]:
    """``randomize.generate``: a kind or a list of kinds, checked."""
    if value is None:
        return ()
    listed = isinstance(value, (list, tuple))
    kinds = list(value) if listed else [value]
    if listed and not 0 < len(kinds) <= MAX_FAMILIES:
        raise ScenarioError(source, "randomize.generate", f"must list 1 to {MAX_FAMILIES} kinds "
                                                          f"(got {len(kinds)})")
    for i, kind in enumerate(kinds):
        if kind not in KINDS:
            where = f"randomize.generate[{i}]" if listed else "randomize.generate"
            raise ScenarioError(source, where, f"must be one of {', '.join(KINDS)} "
                                               f"(got {kind!r:.60})")
    return tuple(kinds)


def _maps(value: Any, source: str) -> tuple[str, ...]:
    """``randomize.maps``: a list of ROS map files, resolved (as given, else against the
    shipped scenarios folders) and checked to exist."""
    from pymunk_bot.config.loader import shipped_scenario_dirs

    if value is None:
        return ()
    if not isinstance(value, (list, tuple)) or not 0 < len(value) <= MAX_FAMILIES:
        raise ScenarioError(source, "randomize.maps", f"must list 1 to {MAX_FAMILIES} ROS map "
                                                      f"files (.yaml) (got {value!r:.60})")
    paths = []
    for i, item in enumerate(value):
        if not isinstance(item, (str, Path)) or Path(item).suffix not in (".yaml", ".yml"):
            raise ScenarioError(source, f"randomize.maps[{i}]", "must be a ROS map file "
                                                                f"(.yaml) (got {item!r:.60})")
        found = [p for p in [Path(item), *(d / item for d in shipped_scenario_dirs())]
                 if p.is_file()]
        if not found:
            raise ScenarioError(source, f"randomize.maps[{i}]",
                                f"no such map file: {item} (relative paths are tried from "
                                f"here and from the shipped scenarios folder)")
        paths.append(str(found[0].resolve()))
    return tuple(paths)
