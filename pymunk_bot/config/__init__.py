"""Scenario configuration: parse, validate, freeze. Imports no physics."""
from .loader import load_scenario, parse_scenario, resolve, scenario_data, shipped_scenarios
from .schema import ScenarioConfig

__all__ = ["ScenarioConfig", "load_scenario", "parse_scenario", "resolve", "scenario_data",
           "shipped_scenarios"]
