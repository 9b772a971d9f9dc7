"""Scenario configuration: parse, validate, freeze. Imports no physics.

The names below load on first use, so a module that needs only ``config.errors`` (the command
line's start, every error path) does not pay for the schema and its checks.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pymunk_bot.config.loader import (load_scenario, parse_scenario, resolve, scenario_data,
                                          shipped_scenarios)
    from pymunk_bot.config.schema import ScenarioConfig

_EXPORTS = {"load_scenario": "loader", "parse_scenario": "loader", "resolve": "loader",
            "scenario_data": "loader", "shipped_scenarios": "loader", "ScenarioConfig": "schema"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        import importlib

        value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
