"""Seeded mutations of scenario files, for fuzzing the loader and the run (see fuzz.py).

Each mutation takes the parsed data of a shipped scenario and a ``numpy.random.Generator`` and
returns YAML text: keys deleted or misspelt, values of the wrong type, extreme numbers, huge
counts, deep nesting, alias bombs, degrees for radians, broken text.
"""
from __future__ import annotations

import copy
import math
from typing import Any, Callable

import numpy as np
import yaml

EXTREMES = [0, -1, 1e-310, 1e-150, 1e154, 1e300, 1.7e308, -1.7e308, 2**70, 10**9, 1000000,
            0.5, 90, 1e6, -1e6, 5000, 100000, 1e-9, float("nan"), float("inf")]
WRONG_TYPES = [None, True, "abc", "1.0", [], {}, [1, 2, 3], {"a": 1}, [[1, 2], [3]], ""]
COUNT_KEYS = ["beams", "time_samples", "v_samples", "w_samples", "substeps"]


def _paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    """Every key path into a nested structure of dicts and lists."""
    out = []
    if isinstance(node, dict):
        for key, value in node.items():
            out.append(prefix + (key,))
            out += _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out.append(prefix + (i,))
            out += _paths(value, prefix + (i,))
    return out


def _parent(data: Any, path: tuple) -> Any:
    for part in path[:-1]:
        data = data[part]
    return data


def _pick(rng: np.random.Generator, items: list) -> Any:
    return items[int(rng.integers(len(items)))]


def delete_key(data: dict, rng: np.random.Generator) -> str:
    paths = [p for p in _paths(data) if isinstance(_parent(data, p), dict)]
    path = _pick(rng, paths)
    del _parent(data, path)[path[-1]]
    return yaml.safe_dump(data)


def wrong_type(data: dict, rng: np.random.Generator) -> str:
    path = _pick(rng, _paths(data))
    _parent(data, path)[path[-1]] = copy.deepcopy(_pick(rng, WRONG_TYPES))
    return yaml.safe_dump(data)


def extreme_number(data: dict, rng: np.random.Generator) -> str:
    paths = [p for p in _paths(data) if isinstance(_get(data, p), (int, float))
             and not isinstance(_get(data, p), bool)]
    if not paths:
        return wrong_type(data, rng)
    for _ in range(int(rng.integers(1, 4))):
        path = _pick(rng, paths)
        _parent(data, path)[path[-1]] = _pick(rng, EXTREMES)
    return yaml.safe_dump(data)


def _get(data: Any, path: tuple) -> Any:
    for part in path:
        data = data[part]
    return data


def huge_count(data: dict, rng: np.random.Generator) -> str:
    robot = _pick(rng, data["robots"])
    kind = int(rng.integers(6))
    big = int(_pick(rng, [5000, 100000, 10**6, 10**9]))
    if kind == 0:
        robot["lidar"] = {"beams": big}
    elif kind == 1:
        robot["controller"] = {"type": "avoid", "dwa": {_pick(rng, COUNT_KEYS[1:4]): big}}
        robot["lidar"] = {"beams": 90}
    elif kind == 2:
        data["obstacles"] = [{"type": "circle", "center": [0.5, 0.5], "radius": 0.01}] * min(
            big, 6000)
    elif kind == 3:
        t = np.linspace(0.0, 2 * math.pi, min(big, 6000), endpoint=False)
        cx, cy = (s / 2 for s in data["world"].get("size") or [6.0, 4.0])  # a map: no size
        points = np.column_stack([cx + 0.3 * np.cos(t), cy + 0.3 * np.sin(t)]).tolist()
        data["obstacles"] = [{"type": "polygon", "points": points}]
    elif kind == 4:
        robot["controller"] = {"type": "waypoints", "points": [[1.0, 1.0]] * min(big, 20000)}
    else:
        data["world"]["size"] = [2000.0, 2000.0]
        robot["controller"] = {"type": "navigate", "resolution": 0.01}
    return yaml.safe_dump(data)


def far_away(data: dict, rng: np.random.Generator) -> str:
    robot = _pick(rng, data["robots"])
    far = float(_pick(rng, [1e3, 1e6, 1e154, -50.0]))
    kind = int(rng.integers(3))
    if kind == 0:
        robot["controller"] = {"type": "waypoints", "points": [[far, far], [1.0, 1.0]]}
    elif kind == 1:
        data.setdefault("obstacles", []).append({"type": "box", "center": [far, 2.0],
                                                 "size": [0.5, 0.5]})
    else:
        robot["goal"] = {"position": [far, 1.0]}
    return yaml.safe_dump(data)


def semantic(data: dict, rng: np.random.Generator) -> str:
    robot = _pick(rng, data["robots"])
    kind = int(rng.integers(6))
    if kind == 0:
        robot.pop("lidar", None)
        robot["controller"] = {"type": _pick(rng, ["avoid", "navigate"])}
        data["robots"].append({"name": "zz-other", "pose": [0.3, 0.3, 0.0], "radius": 0.1})
    elif kind == 1:
        robot.pop("goal", None)
        robot["controller"] = {"type": "go_to_goal"}
        data.pop("expect", None)
    elif kind == 2:
        data["expect"] = {robot["name"]: {"end_in": []}}
    elif kind == 3:
        robot["controller"] = {"type": "python",
                               "class_path": "pymunk_bot.controllers:Controller"}
    elif kind == 4:
        robot["pose"] = list(robot["pose"][:2]) + [90.0]
    else:
        robot["controller"] = {"type": "python", "class_path": "no_such_module_xyz:Thing"}
    return yaml.safe_dump(data)


def deep_nesting(data: dict, rng: np.random.Generator) -> str:
    depth = int(_pick(rng, [40, 500, 5000]))
    return yaml.safe_dump(data) + "extra: " + "[" * depth + "]" * depth + "\n"


def alias_bomb(data: dict, rng: np.random.Generator) -> str:
    lines = ['a0: &a0 ["x", "x", "x", "x", "x", "x", "x", "x", "x", "x"]']
    for k in range(1, int(rng.integers(4, 10))):
        refs = ", ".join([f"*a{k - 1}"] * 10)
        lines.append(f"a{k}: &a{k} [{refs}]")
    return "\n".join(lines) + "\n" + yaml.safe_dump(data)


def broken_text(data: dict, rng: np.random.Generator) -> str:
    text = yaml.safe_dump(data)
    kind = int(rng.integers(6))
    if kind == 0:
        return text[: int(rng.integers(len(text)))]
    if kind == 1:
        i = int(rng.integers(len(text)))
        return text[:i] + _pick(rng, ["\t", ":", "- ", "{", "]", "&", "*x", "!!float abc",
                                      "\x00", "? [1, 2]\n"]) + text[i:]
    if kind == 2:
        return text + "name: twice\n"
    if kind == 3:
        return "base: &base " + "{seed: 3}\n" + text.replace("seed:", "<<: *base\nseedx:", 1)
    if kind == 4:
        return "[1, 2]: 3\n" + text
    return text + "seed: !!float abc\n"


def misspelt_key(data: dict, rng: np.random.Generator) -> str:
    paths = [p for p in _paths(data) if isinstance(_parent(data, p), dict)]
    path = _pick(rng, paths)
    parent = _parent(data, path)
    key = str(path[-1])
    parent[key[:-1] + key[-1] * 2] = parent.pop(path[-1])
    return yaml.safe_dump(data)


MUTATIONS: list[Callable[[dict, np.random.Generator], str]] = [
    delete_key, wrong_type, extreme_number, huge_count, far_away, semantic, deep_nesting,
    alias_bomb, broken_text, misspelt_key,
]


def mutate(data: dict, rng: np.random.Generator) -> tuple[str, str]:
    """(mutation name, YAML text) of one random mutation of ``data`` (left unchanged)."""
    mutation = _pick(rng, MUTATIONS)
    return mutation.__name__, mutation(copy.deepcopy(data), rng)
