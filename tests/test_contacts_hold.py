"""Contacts hold at every speed, acceleration and dt a scenario allows: no robot passes an
obstacle, no pushed crate passes a wall, no contact deeper than 1 cm (a seeded subset of the
bench's 1000 randomized trials: `python -m pymunk_bot.benchmarks.contacts`)."""
from __future__ import annotations

import pytest

from pymunk_bot.benchmarks.contacts import run_trials


@pytest.mark.parametrize("seed", [11, 12])
def test_randomized_contacts_hold(seed):
    summary = run_trials(24, seed=seed)
    assert summary.trials == 24 and set(summary.by_kind) == {"wall", "post", "crate", "head-on"}
    assert summary.crossings == 0, summary.by_kind
    assert summary.max_penetration <= 0.01, summary.by_kind
