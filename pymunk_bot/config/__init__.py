"""Scenario configuration: parse, validate, freeze. Imports no physics."""
from pymunk_bot.config.loader import load_scenario, parse_scenario, resolve, scenario_data, shipped_scenarios
from pymunk_bot.config.schema import ScenarioConfig

__all__ = ["ScenarioConfig", "load_scenario", "parse_scenario", "resolve", "scenario_data",
           "shipped_scenarios"]
