"""Reeds-Shepp and Dubins paths end exactly at the goal pose; reversing makes them shorter."""
from __future__ import annotations

import math

import numpy as np
import pytest

from pymunk_bot.planning import dubins, reeds_shepp


def poses(seed: int, n: int):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield rng.uniform(-3, 3, 3), rng.uniform(-3, 3, 3)


def test_paths_reach_the_goal_pose_and_reversing_is_never_longer():
    found, shorter = 0, 0
    for start, goal in poses(1, 300):
        forward = dubins.shortest(start, goal, 0.7)
        assert forward is not None  # a Dubins path always exists
        sampled = dubins.sample(start, forward, 0.7, 0.05)
        assert np.allclose(sampled[-1, :2], goal[:2], atol=1e-6)
        both = reeds_shepp.shortest(start, goal, 0.7)
        if both is None:
            continue  # a word family we do not implement (CCCC, CCSC, ...)
        found += 1
        end, directions = reeds_shepp.sample(start, both, 0.7, 0.05)
        assert np.allclose(end[-1, :2], goal[:2], atol=1e-6)
        assert math.remainder(end[-1, 2] - goal[2], 2 * math.pi) == pytest.approx(0, abs=1e-6)
        length = sum(abs(v) for _, v in both)
        assert length <= sum(v for _, v in forward) + 1e-9
        shorter += length < sum(v for _, v in forward) - 1e-6
        assert set(np.unique(directions)) <= {-1.0, 1.0}
    assert found >= 0.95 * 300 and shorter > 100


def test_a_sideways_shift_is_a_parking_manoeuvre_with_reversing():
    segments = reeds_shepp.shortest((0.0, 0.0, 0.0), (0.0, -0.6, 0.0), 0.5)
    assert segments is not None
    assert any(length < 0 for _, length in segments)
    assert sum(abs(v) for _, v in segments) < 2.5
