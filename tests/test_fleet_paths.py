"""A robot moves the same in a fleet of any size: the batched tick (pymunk.batch, arrays) and
the per-robot tick (floats) give the very same poses, held steps included."""
from __future__ import annotations

import sys

import numpy as np
import pytest

from bench.fleet import swarm_scenario
from pymunk_bot.engine.simulation import Simulation


def _run(monkeypatch: pytest.MonkeyPatch, small_below: int, seconds: float) -> np.ndarray:
    """Every robot's pose after ``seconds`` of the 30-robot swarm, with the per-robot path
    taken below ``small_below`` robots."""
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("pymunk_bot") and hasattr(module, "SMALL_GROUP"):
            monkeypatch.setattr(module, "SMALL_GROUP", small_below)
    sim = Simulation.from_dict(swarm_scenario(30), source="swarm")
    assert sim._built.propulsion.batched == (small_below <= 30)
    sim.run(seconds)
    return np.array([robot.pose for robot in sim.robots.values()])


def test_batched_and_per_robot_ticks_agree_to_the_bit(monkeypatch: pytest.MonkeyPatch) -> None:
    # The swarm's robots hold steady arcs, meet and push each other: held steps and contacts.
    batched = _run(monkeypatch, 24, 3.0)
    per_robot = _run(monkeypatch, 1000, 3.0)
    assert np.array_equal(batched, per_robot)
    assert np.ptp(batched[:, :2], axis=0).min() > 1.0  # they did move
