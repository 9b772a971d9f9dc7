"""Scenario files -> validated, frozen ScenarioConfig (or one ScenarioError)."""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from pymunk_bot.config.errors import ScenarioError, ScenarioWarning, SemanticError
from pymunk_bot.config import semantics
from pymunk_bot.config.assemble import scenario_model
from pymunk_bot.config.checks import angle_warnings
from pymunk_bot.config.messages import describe, most_helpful, walk
from pymunk_bot.config.schema import ScenarioConfig
from pymunk_bot.config.world_map import attach_map
from pymunk_bot.config.yaml_source import line_of, parse_yaml, read_text

PACKAGE_DATA = Path(__file__).resolve().parent  # the built-in default scenario lives here
DEFAULT_SCENARIO = PACKAGE_DATA / "default.yaml"


def shipped_scenario_dirs() -> list[Path]:
    """Where shipped scenarios live: ./scenarios, then the source checkout's scenarios/."""
    candidates = [Path.cwd() / "scenarios", PACKAGE_DATA.parent.parent / "scenarios"]
    seen, dirs = set(), []
    for d in candidates:
        if d.is_dir() and d.resolve() not in seen:
            seen.add(d.resolve())
            dirs.append(d)
    return dirs


def shipped_scenarios() -> dict[str, Path]:
    """Name -> path of every shipped scenario, the built-in default first."""
    found = {"default": DEFAULT_SCENARIO}
    for d in shipped_scenario_dirs():
        for path in sorted(d.glob("*.yaml")):
            found.setdefault(path.stem, path)
    return found


def resolve(spec: str | Path | None) -> Path:
    """A scenario path, or the name of a shipped one; None means the built-in default."""
    if spec is None:
        return DEFAULT_SCENARIO
    path = Path(spec)
    if path.exists() or path.suffix in (".yaml", ".yml") or "/" in str(spec):
        return path
    shipped = shipped_scenarios()
    if str(spec) in shipped:
        return shipped[str(spec)]
    from pymunk_bot.config.messages import did_you_mean
    raise ScenarioError(str(spec), "", "no such file or shipped scenario"
                        f"{did_you_mean(str(spec), shipped)}; see `pymunk-bot list`")


def parse_scenario(data: Any, source: str, node=None,
                   base_dir: str | Path | None = None) -> ScenarioConfig:
    """Validate already-parsed data; ``node`` (a YAML node tree) adds line numbers.

    ``source`` names the data in errors; when it is a file's path, a relative ``world.map`` is
    resolved against that file's directory (else against the current directory). ``base_dir``
    (the file's folder) is where a python controller's module is looked for first."""
    if not isinstance(data, dict):
        raise ScenarioError(source, "", "the file must be a YAML mapping of scenario keys "
                                        f"(got {type(data).__name__})")
    model = scenario_model()
    try:
        context = {"base_dir": None if base_dir is None else str(base_dir)}
        config = model.model_validate(data, context=context)
    except ValidationError as exc:
        errors: list[dict[str, Any]] = [dict(e) for e in exc.errors()]
        first = most_helpful(errors)
        loc = first["loc"]
        if first["type"] == "missing" and loc and isinstance(loc[-1], int):
            loc = loc[:-1]  # a short list: name the list, not its absent item
        path, clean_loc, owner = walk(model, loc)
        more = _more_problems(errors, first)
        raise ScenarioError(source, path, describe(first, owner) + more,
                            line_of(node, clean_loc)) from None
    config = attach_map(config, source, node)
    try:
        semantics.check(config)
    except SemanticError as exc:
        path, clean_loc, _ = walk(model, exc.loc)
        raise ScenarioError(source, path, exc.problem, line_of(node, clean_loc)) from None
    for loc, problem in angle_warnings(config):
        path, clean_loc, _ = walk(model, loc)
        warnings.warn(ScenarioWarning(source, path, problem, line_of(node, clean_loc)),
                      stacklevel=2)
    return config


def scenario_data(config: ScenarioConfig, exclude_unset: bool = False) -> dict:
    """The config as plain data that :func:`parse_scenario` turns back into it, from any
    folder: a map world's ``size`` (the parser filled it in) is left out and its map path is
    the resolved one. ``exclude_unset``: only the keys the scenario gave."""
    data = config.model_dump(exclude_unset=exclude_unset)
    if config.world.map is not None:
        data["world"].pop("size", None)
        if config.world.map_path is not None:
            data["world"]["map"] = config.world.map_path
    return data


def _more_problems(errors: list[dict], first: dict) -> str:
    """How many other problems pydantic found, worded so it cannot be read as the end of a
    list of valid keys; a misspelt key's 'missing' twin is the same problem, not another."""
    parent = first["loc"][:-1]
    others = [e for e in errors if e is not first and not (
        first["type"] == "extra_forbidden" and e["type"] == "missing" and e["loc"][:-1] == parent)]
    if not others:
        return ""
    return f"; {len(others)} more problem{'s' if len(others) > 1 else ''} in the file"


def load_scenario(spec: str | Path | None = None) -> ScenarioConfig:
    """Read and validate a scenario file (path or shipped name; None = built-in default)."""
    path = resolve(spec)
    source = str(spec) if spec is not None and Path(str(spec)).exists() else str(path)
    text = read_text(path, source)
    data, node = parse_yaml(text, source)
    return parse_scenario(data, source, node, base_dir=path.resolve().parent)


ScenarioConfig.full_validation = parse_scenario  # ScenarioConfig.model_validate(data) validates fully
