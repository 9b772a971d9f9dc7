"""Global localization and kidnap recovery in Nav2's warehouse map, with active localization
(MCL's ``explore_heading`` followed by the localizing controller).

Before (robustness benchmark, issue 20's third pass): global seed 1 converged after 90 s,
kidnapping seed 0 after 32 s; the robot turned a full circle on the spot, then crept along an
aisle whose 180-degree twin fitted every scan as well. Slow: the warehouse runs take ~10 s each.
"""
from __future__ import annotations

import pytest

from pymunk_bot.benchmarks import localization_robustness as bench

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not bench.WAREHOUSE.exists(), reason="no warehouse map")]


@pytest.mark.parametrize("localizer, seed", [("mcl_global", 1), ("mcl_kidnap", 0)])
def test_the_warehouse_look_alike_aisles_are_told_apart_within_20_s(localizer, seed):
    outcome = bench.run_one(localizer, "warehouse", "typical", seed)
    assert outcome is not None and not outcome.error
    assert outcome.converged_at <= bench.GLOBAL_TIME, outcome.line()
    assert outcome.collisions == 0
    assert outcome.wrong_localized == 0.0, "drove on a wrong hypothesis"
