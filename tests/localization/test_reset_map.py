"""A run's reset keeps what it derived from its map (the occupancy grid, the localizers'
likelihood fields: building them was most of an MCL or EKF scenario's reset) and plays the
same run a fresh build of that seed plays."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot.engine.simulation import Simulation


@pytest.mark.parametrize("scenario", ["mcl_office", "ekf_office"])
def test_a_reset_keeps_the_map_fields_and_plays_the_fresh_run(scenario):
    sim = Simulation.from_file(scenario)
    name = next(n for n, r in sim.robots.items() if getattr(r.localizer, "field", None))
    field = sim.robots[name].localizer.field
    sim.run(1.0)
    sim.reset(seed=7)
    assert sim.robots[name].localizer.field is field  # kept, not built again
    sim.run(3.0)
    fresh = Simulation.from_file(scenario, seed=7)
    fresh.run(3.0)
    assert fresh.robots[name].localizer.field is not field
    for robot in sim.robots:
        assert np.array_equal(sim.robots[robot].pose, fresh.robots[robot].pose)
        assert np.array_equal(sim.robots[robot].localizer.pose, fresh.robots[robot].localizer.pose)
    assert sim.result()["robots"] == fresh.result()["robots"]
