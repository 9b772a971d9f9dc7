"""Whatever a user writes, loading gives a config or one ScenarioError, never another exception."""
from __future__ import annotations

import re
from pathlib import Path

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pymunk_bot import ScenarioError, Simulation
from pymunk_bot.config import parse_scenario

BASE = {
    "name": "fuzz",
    "world": {"size": [10.0, 5.0]},
    "obstacles": [{"type": "box", "center": [5.0, 2.5], "size": [1.0, 1.0]}],
    "robots": [{"name": "r1", "pose": [1.0, 2.5, 0.0], "lidar": {"beams": 10},
                "controller": {"type": "go_to_goal"}, "goal": {"position": [9.0, 4.0]}}],
    "expect": {"r1": {"goal_reached": True}},
}
PATHS = [("name",), ("seed",), ("world", "size"), ("world", "dt"), ("world", "substeps"),
         ("obstacles", 0, "center"), ("obstacles", 0, "size"), ("obstacles", 0, "type"),
         ("robots", 0, "pose"), ("robots", 0, "radius"), ("robots", 0, "lidar", "beams"),
         ("robots", 0, "lidar", "fov"), ("robots", 0, "controller", "type"),
         ("robots", 0, "goal", "position"), ("expect", "r1", "within"), ("robots", 0, "name")]
values = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                   st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=8),
                   st.lists(st.floats(-100, 100), max_size=4), st.dictionaries(st.text(max_size=4),
                                                                              st.integers(), max_size=2))


def replaced(data, path, value):
    import copy
    out = copy.deepcopy(data)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(PATHS), value=values)
def test_any_value_anywhere_is_accepted_or_rejected_cleanly(path, value):
    try:
        config = parse_scenario(replaced(BASE, path, value), "fuzz.yaml")
    except ScenarioError as exc:
        message = str(exc)
        assert "\n" not in message and message.startswith("fuzz.yaml: ")
    else:
        Simulation(config).run(0.1)  # whatever validates also builds and runs


def test_example_in_the_docs_is_a_valid_scenario_that_passes():
    text = (Path(__file__).resolve().parent.parent / "docs" / "scenario-format.md").read_text()
    block = re.search(r"## A complete example\s+```yaml\n(.*?)```", text, re.S).group(1)
    sim = Simulation(parse_scenario(yaml.safe_load(block), "docs"))
    sim.run(sim.config.world.duration)
    assert all(c.passed for c in sim.check_expectations())
