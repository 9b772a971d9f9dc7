"""The scenario schema, assembled from the registries: every drive, obstacle kind, sensor,
controller and localizer brings its own pydantic model, so a plugin's keys are checked, and its
errors worded, exactly like the built-ins'.

The assembled models subclass the static ones in ``schema`` (so ``isinstance`` and type hints
keep working) and are rebuilt only when a registry changes.
"""
from __future__ import annotations

from typing import Annotated, Any, Union

from pydantic import BeforeValidator, Discriminator, Field, Tag, create_model

from pymunk_bot import plugins
from pymunk_bot.config.schema import RobotConfig, ScenarioConfig
from pymunk_bot.config.types import MAX_OBSTACLES, MAX_ROBOTS

_cache: dict[str, Any] = {"key": None, "model": None}


def _tagged_union(models: list[type], field: str) -> Any:
    """A union of models told apart by their ``field`` (a Literal) value."""
    if len(models) == 1:
        return models[0]
    return Annotated[Union[tuple(models)], Field(discriminator=field)]


def _as_section(value: Any) -> Any:
    """``localization: mcl`` is short for ``localization: {type: mcl}``."""
    return {"type": value} if isinstance(value, str) else value


def _drive_of(value: Any) -> str:
    if isinstance(value, dict):
        drive = value.get("drive", "diff")
        return drive if isinstance(drive, str) else repr(drive)
    return str(getattr(value, "drive", "diff"))


def _robot_models() -> Any:
    controllers = [e.config for e in plugins.controllers.entries()]
    localizers = [e.config for e in plugins.localizers.entries()]
    controller_union = _tagged_union(controllers, "type")
    localizer_union = Annotated[_tagged_union(localizers, "type"),  # type: ignore[valid-type]
                                BeforeValidator(_as_section)]
    sensor_fields = {e.name: (e.config | None, None) for e in plugins.sensors.entries()
                     if e.name not in RobotConfig.model_fields}
    members = []
    for entry in plugins.drives.entries():
        model = create_model(  # type: ignore[call-overload]  # field types built at run time
            entry.config.__name__, __base__=entry.config, __module__=entry.config.__module__,
            controller=(controller_union | None, None),
            localization=(localizer_union, Field(default="odometry", validate_default=True)),
            **sensor_fields)
        members.append(Annotated[model, Tag(entry.name)])
    if len(members) == 1:
        return members[0]
    return Annotated[Union[tuple(members)], Discriminator(_drive_of)]


def obstacle_union() -> Any:
    """The type of one ``obstacles`` item: a union of every registered obstacle kind's model."""
    plugins.load()
    return _tagged_union([e.config for e in plugins.obstacles.entries()], "type")


def scenario_model() -> type[ScenarioConfig]:
    """The ScenarioConfig model for everything registered now (built once per registry state)."""
    plugins.load()
    key = plugins.state()
    if _cache["key"] != key:
        obstacles = obstacle_union()
        _cache["model"] = create_model(
            "ScenarioConfig", __base__=ScenarioConfig, __module__=ScenarioConfig.__module__,
            obstacles=(list[obstacles], Field([], max_length=MAX_OBSTACLES)),  # type: ignore[valid-type]
            robots=(list[_robot_models()],  # type: ignore[misc,arg-type]
                    Field(min_length=1, max_length=MAX_ROBOTS)))
        _cache["key"] = key
    return _cache["model"]
