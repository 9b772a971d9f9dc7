"""One path at every size: a robot steered alone and as one of a fleet of 30 gets the very same
poses, to the bit (held steps, straight ones and ramping motors included)."""
from __future__ import annotations

from typing import Any

import numpy as np

from pymunk_bot.engine.simulation import Simulation


def _robot(k: int) -> dict[str, Any]:
    """Robot ``k`` of a 6 x 5 grid 8 m apart: each its own wheel speeds (some straight)."""
    left = 0.3 + 0.05 * (k % 7)
    right = left if k % 5 == 0 else left + 0.04 * (1 + k % 3)
    return {"name": f"r{k}", "pose": [6.0 + 8.0 * (k % 6), 6.0 + 8.0 * (k // 6), 0.2 * k],
            "controller": {"type": "wheels", "left": left, "right": right}}


def _poses(robots: list[dict[str, Any]], seconds: float) -> np.ndarray:
    # A substep count of its own: the default's, where contacts can start, is shared by a
    # Space's robots (the fleet's fastest sets it), which would differ alone.
    sim = Simulation.from_dict({"name": "fleet", "world": {"size": [52.0, 44.0], "substeps": 3},
                                "robots": robots}, source="fleet")
    sim.run(seconds)
    return np.array([robot.pose for robot in sim.robots.values()])


def test_a_robot_moves_alone_as_in_a_fleet_to_the_bit() -> None:
    fleet = _poses([_robot(k) for k in range(30)], 4.0)
    for k in (0, 7, 13, 29):  # straight (0), turning (7, 13, 29)
        alone = _poses([_robot(k)], 4.0)
        assert np.array_equal(alone[0], fleet[k]), k
    assert np.ptp(fleet[:, :2], axis=0).min() > 10.0  # they did move (and apart)
    assert abs(fleet[7, 2] - 0.2 * 7) > 0.5  # and turned
