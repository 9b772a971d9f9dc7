"""The general policy (scenarios/policies/navigator.npz) on a real ROS map it never trained on:
Nav2's warehouse (not shipped; the test is skipped where ../shared/maps/warehouse.yaml is not)."""
from __future__ import annotations

from pathlib import Path

import pytest

from pymunk_bot.config import parse_scenario
from pymunk_bot.engine.simulation import Simulation

REPO = Path(__file__).resolve().parents[2]
WAREHOUSE = REPO.parent / "shared" / "maps" / "warehouse.yaml"
NAVIGATOR = REPO / "scenarios" / "policies" / "navigator.npz"


@pytest.mark.skipif(not WAREHOUSE.is_file(), reason="Nav2's warehouse map is not here")
def test_the_general_policy_crosses_the_warehouse_without_contact():
    # From the aisle between the lower shelves up past the middle shelf to the top hall:
    # over 34 m, round the shelf rows.
    data = {"name": "navigator_warehouse", "seed": 0,
            "world": {"map": str(WAREHOUSE), "duration": 90.0},
            "robots": [{"name": "r1", "pose": [-6.0, -18.0, 0.0], "radius": 0.2,
                        "max_wheel_speed": 0.8, "localization": "ground_truth",
                        "lidar": {"beams": 32, "max_range": 4.0, "noise_std": 0.01},
                        "goal": {"position": [2.0, 16.0], "tolerance": 0.25},
                        "controller": {"type": "policy", "path": str(NAVIGATOR)}}],
            "expect": {"r1": {"goal_reached": True, "max_collisions": 0}}}
    sim = Simulation(parse_scenario(data, "navigator_warehouse"))
    sim.run(90.0)
    assert [c.describe() for c in sim.check_expectations() if not c.passed] == []
