"""The sweep grid: `--set key.path=v1,v2` assignments times seeds, checked before anything runs.

A key path is any scenario key path as error messages print it (``world.dt``,
``robots[0].lidar.beams``); values are YAML scalars or flow collections (``0.5``, ``true``,
``[10, 4]``), separated by commas outside brackets.
"""
from __future__ import annotations

import copy
import itertools
import re
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import yaml

from pymunk_bot.config import ScenarioConfig, parse_scenario, scenario_data
from pymunk_bot.config.errors import ScenarioError

MAX_COMBINATIONS = 10_000  # distinct parameter combinations in one sweep
MAX_RUNS = 1_000_000  # combinations x seeds
MAX_SEED = 2**32 - 1
_PATH = re.compile(r"[A-Za-z_]\w*(?:\[\d+\]|\.[A-Za-z_]\w*)*")
_TOKEN = re.compile(r"([A-Za-z_]\w*)|\[(\d+)\]")


@dataclass(frozen=True)
class Run:
    """One simulation of the sweep: its index in the grid, the swept values and the seed."""

    index: int
    values: tuple[tuple[str, Any], ...]  # (key path, value) in --set order
    seed: int


def parse_key_path(path: str) -> list[str | int]:
    """``robots[0].lidar.beams`` -> ["robots", 0, "lidar", "beams"] (ValueError if malformed)."""
    if not _PATH.fullmatch(path):
        raise ValueError(f"malformed key path '{path}' (expected e.g. robots[0].lidar.beams)")
    return [name if name else int(index) for name, index in _TOKEN.findall(path)]


def split_values(text: str) -> list[str]:
    """Split on commas that are not inside brackets or braces."""
    parts, depth, current = [], 0, ""
    for ch in text:
        if ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    parts.append(current)
    return [p.strip() for p in parts]


def parse_assignment(text: str) -> tuple[str, list[Any]]:
    """``key.path=v1,v2`` -> (key path, [values]); ValueError names what is wrong."""
    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ValueError(f"'{text}': expected KEY.PATH=VALUE[,VALUE...]")
    parse_key_path(key)
    parsed = []
    for raw in split_values(values):
        if raw == "":
            raise ValueError(f"'{text}': empty value")
        try:
            parsed.append(yaml.safe_load(raw))
        except yaml.YAMLError:
            raise ValueError(f"'{text}': cannot read value '{raw}'") from None
    return key, parsed


def parse_seeds(text: str) -> list[int]:
    """``0:20`` (start:stop, stop excluded), ``3,5,9`` or ``7`` -> seeds."""
    seeds: list[int] = []
    try:
        for part in text.split(","):
            if ":" in part:
                start, stop = (int(v) for v in part.split(":", 1))
                if stop <= start:
                    raise ValueError
                seeds.extend(range(start, min(stop, start + MAX_RUNS + 1)))
            else:
                seeds.append(int(part))
    except ValueError:
        raise ValueError(f"seeds '{text}': expected START:STOP (STOP > START), "
                         "a list like 1,2,3 or one seed") from None
    if not seeds or min(seeds) < 0 or max(seeds) > MAX_SEED:
        raise ValueError(f"seeds '{text}': each seed must be in [0, {MAX_SEED}]")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds '{text}': a seed is listed twice")
    return seeds


def apply_override(data: dict, path: str, value: Any) -> None:
    """Set ``value`` at ``path`` in a scenario mapping (made with ``model_dump``), in place.

    A list index must exist; a missing mapping key is created (validation then names an
    unknown key); a section that is off (``lidar: null``) is switched on with its defaults.
    """
    tokens = parse_key_path(path)
    node: Any = data
    for depth, token in enumerate(tokens):
        where = _format(tokens[: depth + 1])
        last = depth == len(tokens) - 1
        if isinstance(token, int):
            if not isinstance(node, list):
                raise KeyError(where, "is not a list")
            if token >= len(node):
                raise KeyError(where, f"no such item (the list has {len(node)})")
            if last:
                node[token] = value
            else:
                node = node[token]
            continue
        if not isinstance(node, dict):
            raise KeyError(where, f"'{_format(tokens[:depth])}' has no keys")
        if last:
            node[token] = value
        else:
            if node.get(token) is None:
                node[token] = {} if isinstance(tokens[depth + 1], str) else []
            node = node[token]


def _format(tokens: Sequence[str | int]) -> str:
    out = ""
    for t in tokens:
        out += f"[{t}]" if isinstance(t, int) else (f".{t}" if out else t)
    return out


def scenario_with(base: dict, values: Iterable[tuple[str, Any]]) -> dict:
    data = copy.deepcopy(base)
    for path, value in values:
        apply_override(data, path, value)
    return data


def build_grid(config: ScenarioConfig, source: str, grid: dict[str, list[Any]],
               seeds: Sequence[int], base_dir: str | None = None) -> list[Run]:
    """Every combination of ``grid`` values times ``seeds``, each combination validated as a
    scenario first (Python controllers looked for in ``base_dir`` first): a bad path or value
    raises ScenarioError naming it, before any run."""
    for path, values in grid.items():
        if not values:
            raise ScenarioError(source, path, "--set needs at least one value")
        if len(set(map(repr, values))) != len(values):
            raise ScenarioError(source, path, "a value is listed twice")
    combinations = list(itertools.product(*grid.values())) if grid else [()]
    if len(combinations) > MAX_COMBINATIONS:
        raise ScenarioError(source, "", f"{len(combinations)} parameter combinations; at most "
                                        f"{MAX_COMBINATIONS}")
    if len(combinations) * len(seeds) > MAX_RUNS:
        raise ScenarioError(source, "", f"{len(combinations) * len(seeds)} runs; at most {MAX_RUNS}")
    base = scenario_data(config)
    keys = list(grid)
    for combo in combinations:
        values = list(zip(keys, combo))
        try:
            data = scenario_with(base, values)
        except KeyError as exc:
            where, problem = exc.args
            raise ScenarioError(source, where, f"{problem} (--set {_describe(values)})") from None
        try:
            parse_scenario(data, source, base_dir=base_dir)
        except ScenarioError as exc:
            raise ScenarioError(source, exc.path, f"{exc.problem} (with --set "
                                                  f"{_describe(values)})") from None
    return [Run(i * len(seeds) + j, tuple(zip(keys, combo)), int(seed))
            for i, combo in enumerate(combinations) for j, seed in enumerate(seeds)]


def _describe(values: list[tuple[str, Any]]) -> str:
    return " ".join(f"{k}={v}" for k, v in values)
