"""avoid: reaches goals through layouts it was not tuned on without touching anything."""
import numpy as np

from pathlib import Path

from pymunk_bot import Simulation
from pymunk_bot.config import load_scenario

from helpers import clutter_case, parallel, run_until_goal, scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
SEEDS = range(100, 112)  # not the seeds the defaults were tuned on (0-15)


def test_crosses_random_cluttered_fields_without_collisions():
    results = parallel(clutter_case, SEEDS, [{"type": "avoid"}] * len(SEEDS))
    assert sum(r["collisions"] for r in results) == 0
    reached = sum(r["goal_reached"] for r in results)
    assert reached >= 0.8 * len(results), [r["controller_message"] for r in results]


def test_gets_stuck_in_the_u_trap_that_navigate_escapes():
    config = load_scenario(SCENARIOS / "u_trap.yaml")
    data = config.model_dump()
    data["robots"][0]["controller"] = {"type": "avoid"}
    data["expect"] = {}
    from pymunk_bot.config.loader import parse_scenario
    reactive = run_until_goal(parse_scenario(data, "u_trap"), 25.0)["robots"]["r1"]
    planned = run_until_goal(config, 25.0)["robots"]["r1"]
    assert not reactive["goal_reached"]
    assert reactive["collisions"] == 0
    assert planned["goal_reached"] and planned["collisions"] == 0


def test_without_a_lidar_it_refuses_instead_of_driving_blind():
    config = scenario((5.0, 5.0), [], [{"name": "r", "pose": [1.0, 1.0, 0.0],
                                        "controller": {"type": "avoid"},
                                        "goal": {"position": [4.0, 4.0]}}])
    sim = Simulation(config)
    sim.run(2.0)
    robot = sim.robots["r"]
    assert robot.controller.status == "failed" and "lidar" in robot.controller.message
    assert robot.distance < 1e-6
