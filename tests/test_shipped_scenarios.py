"""Every shipped scenario validates, runs headless to its duration and meets its expectations."""
from __future__ import annotations

from pathlib import Path

import pytest

from pymunk_bot import Simulation, load_scenario
from pymunk_bot.config import shipped_scenarios

REPO = Path(__file__).resolve().parent.parent
SHIPPED = {"default": None, **{p.stem: p for p in sorted((REPO / "scenarios").glob("*.yaml"))}}


def test_the_four_foundation_scenarios_are_shipped():
    assert {"open_goal", "wall_headon", "wall_graze", "push_crate"} <= SHIPPED.keys()
    assert "default" in shipped_scenarios()


# The localization scenarios take 5-15 s of CPU each; tests/localization checks what they show
# (SLAM closing a loop, MCL and the EKF in an office), so they run with the slow tests.
LONG = {"slam_loop", "mcl_office", "ekf_office"}


@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.slow) if name in LONG
                                  else name for name in sorted(SHIPPED)])
def test_shipped_scenario_meets_its_expectations(name):
    config = load_scenario(SHIPPED[name])
    assert config.description
    assert config.expect, "a shipped scenario states what it expects"
    sim = Simulation(config)
    sim.run(config.world.duration)
    failed = [c.describe() for c in sim.check_expectations() if not c.passed]
    assert not failed


# The general policy's collision regression tests, one per world family (docs/learning.md).
NAVIGATOR = {"navigator_clutter": "clutter", "navigator_office": "office",
             "navigator_maze": "maze", "navigator_floor": "map"}


def test_the_general_policy_has_a_regression_scenario_in_every_family():
    for name, family in NAVIGATOR.items():
        config = load_scenario(SHIPPED[name])
        controller = config.robots[0].controller
        assert controller.type == "policy" and Path(controller.path).name == "navigator.npz"
        assert (config.world.map is not None) == (family == "map")
        assert config.expect["r1"].max_collisions == 0 and config.expect["r1"].goal_reached
