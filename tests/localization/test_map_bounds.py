"""A localizer given the arena's map at 5 cm is bounded in cells: a huge arena is one line at
validation, not a MemoryError in the middle of building (found by the fuzz harness)."""
from __future__ import annotations

import pytest
from builders import robot, scenario

from pymunk_bot.config import parse_scenario
from pymunk_bot.config.errors import ScenarioError


@pytest.mark.parametrize("kind", ["ekf", "mcl"])
def test_a_map_localizer_on_a_huge_arena_is_refused_with_one_line(kind):
    data = scenario([robot([5, 5, 0], lidar={"beams": 90}, localization=kind)],
                    size=(10_000.0, 8_000.0))
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(data, "huge.yaml")
    message = str(caught.value)
    assert "robots[0].localization" in message and "over the limit" in message
    assert "\n" not in message


def test_a_map_localizer_on_a_200_m_arena_is_accepted():
    data = scenario([robot([5, 5, 0], lidar={"beams": 90}, localization="ekf")],
                    size=(200.0, 200.0))
    parse_scenario(data, "large.yaml")
