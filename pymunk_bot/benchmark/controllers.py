"""What ``--controller`` names: a registered controller type, or a YAML/JSON file holding one
``controller:`` block (the same block as a scenario's, e.g. a user's ``type: python`` class)."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from pymunk_bot.config.errors import ScenarioError


@dataclass(frozen=True)
class ControllerChoice:
    """A controller under test: its name in rows, its block, and where a user's module is."""

    name: str
    block: dict = field(hash=False)
    base_dir: str | None = None  # a controller file's folder (its Python module is there)


def controller_choice(spec: str) -> ControllerChoice:
    """``spec`` -> the controller it names (ScenarioError naming ``--controller`` if none)."""
    from pymunk_bot import plugins

    plugins.load()
    path = Path(spec)
    if path.suffix.lower() in (".yaml", ".yml", ".json") or path.is_file():
        try:
            text = path.read_text(encoding="utf-8")
            data = json.loads(text) if path.suffix.lower() == ".json" else yaml.safe_load(text)
        except OSError as exc:
            raise ScenarioError(spec, "", f"cannot read: {exc.strerror or exc}") from None
        except (ValueError, yaml.YAMLError) as exc:
            raise ScenarioError(spec, "", f"not valid YAML/JSON: {exc}".replace("\n", " ")
                                ) from None
        block = data.get("controller") if isinstance(data, dict) else None
        if not isinstance(block, dict) or "type" not in block:
            raise ScenarioError(spec, "controller", "the file must hold one 'controller:' "
                                                    "mapping with a 'type'")
        return ControllerChoice(path.stem, block, str(path.resolve().parent))
    if spec in plugins.controllers:
        return ControllerChoice(spec, {"type": spec})
    from pymunk_bot.config.messages import did_you_mean
    names = plugins.controllers.names()
    raise ScenarioError("--controller", "", f"'{spec}' is neither a controller type nor a "
                        f"controller file{did_you_mean(spec, names)} (types: {', '.join(names)})")


def controller_choices(specs: list[str]) -> list[ControllerChoice]:
    """Every ``--controller``, each name once."""
    if not specs:
        raise ScenarioError("--controller", "", "name at least one controller")
    choices = [controller_choice(s) for s in specs]
    names = [c.name for c in choices]
    for name in names:
        if names.count(name) > 1:
            raise ScenarioError("--controller", "", f"'{name}' is given twice")
    return choices
