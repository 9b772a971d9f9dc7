"""avoid: reaches goals through layouts it was not tuned on without touching anything."""
import math


from pathlib import Path

import pytest

from pymunk_bot import ScenarioError, Simulation
from pymunk_bot.config import load_scenario

from helpers import clutter_case, parallel, run_until_goal, scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
SEEDS = range(100, 112)  # not the seeds the defaults were tuned on (0-15)


@pytest.mark.slow  # end-to-end, several seconds: .ci/run runs it (-m slow)
def test_crosses_random_cluttered_fields_without_collisions():
    results = parallel(clutter_case, SEEDS, [{"type": "avoid"}] * len(SEEDS))
    assert sum(r["collisions"] for r in results) == 0
    reached = sum(r["goal_reached"] for r in results)
    assert reached >= 0.8 * len(results), [r["controller_message"] for r in results]


def swap_case(width: float, offset: float, seed: int, max_speed: float | None = None) -> dict:
    """Two avoid robots swap places along a line across a width-metre-wide arena (walls on both
    sides), the second one ``offset`` metres to the side; results of both."""
    controller = {"type": "avoid"} if max_speed is None else {"type": "avoid", "max_speed": max_speed}
    lidar = {"beams": 180, "max_range": 5.0, "noise_std": 0.01}
    y = 0.5 * width
    robots = [{"name": "a", "pose": [1.0, y, 0.0], "lidar": lidar, "controller": controller,
               "goal": {"position": [9.0, y]}},
              {"name": "b", "pose": [9.0, y + offset, math.pi], "lidar": lidar,
               "controller": controller, "goal": {"position": [1.0, y + offset]}}]
    return run_until_goal(scenario((10.0, width), [], robots, seed=seed), 30.0)["robots"]


SWAPS = [(6.0, offset, seed, speed) for offset in (0.0, 0.05, -0.1, 0.2) for seed in (0, 1)
         for speed in (None, 0.6)] + [(2.5, offset, seed, None) for offset in (0.0, 0.05, -0.1)
                                      for seed in (0, 1)]


@pytest.mark.slow  # end-to-end, several seconds: .ci/run runs it (-m slow)
def test_two_robots_meeting_head_on_keep_right_and_pass_without_touching():
    results = parallel(swap_case, *zip(*SWAPS))
    failed = [(case, {n: (r["goal_reached"], r["collisions"]) for n, r in robots.items()})
              for case, robots in zip(SWAPS, results)
              if not all(r["goal_reached"] and r["collisions"] == 0 for r in robots.values())]
    assert not failed


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


def test_without_a_lidar_it_is_refused_when_the_file_is_validated():
    with pytest.raises(ScenarioError) as err:
        scenario((5.0, 5.0), [], [{"name": "r", "pose": [1.0, 1.0, 0.0],
                                   "controller": {"type": "avoid"},
                                   "goal": {"position": [4.0, 4.0]}}])
    assert "robots[0].controller: avoid steers by the LiDAR" in str(err.value)
