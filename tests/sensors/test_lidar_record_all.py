"""Many scans stored at once (record_all) are exactly the scans each LiDAR stores alone."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot.sensors.lidar import record_all
from pymunk_bot.engine.simulation import Simulation

LIDARS = [{"beams": 90, "noise_std": 0.01},
          {"beams": 90, "noise_std": 0.05, "dropout": 0.2, "min_range": 0.5, "max_range": 4.0},
          {"beams": 90},  # exact ranges
          {"beams": 90, "dropout": 0.3},  # dropout without noise
          {"beams": 90, "noise_std": 0.002, "max_range": 12.0},
          {"beams": 90, "min_range": 0.5, "max_range": 6.0}]  # exact, other limits
ANOTHER_COUNT = {"beams": 45, "noise_std": 0.01}  # mixed beam counts: stored one by one


def _lidars(lidars):
    robots = [{"name": f"r{i}", "pose": [1.0 + 1.5 * i, 1.0, 0.0], "lidar": lidar}
              for i, lidar in enumerate(lidars)]
    sim = Simulation.from_dict({"name": "scans", "world": {"size": [12.0, 3.0]},
                                "robots": robots}, seed=4)
    return [robot.lidar for robot in sim.robots.values()]


@pytest.mark.parametrize("lidars", [LIDARS, LIDARS + [ANOTHER_COUNT]])
def test_scans_stored_together_equal_scans_stored_alone(lidars):
    alone, together = _lidars(lidars), _lidars(lidars)
    rng = np.random.default_rng(0)
    for tick in range(5):  # the random streams stay in step scan after scan
        truth = [rng.uniform(0.0, 13.0, lidar.config.beams) for lidar in alone]
        truth[0][:5] = [0.0, 0.3, 4.0, 8.0, 13.0]  # at and beyond the limits
        for lidar, ranges in zip(alone, truth):
            lidar.record(0.1 * tick, ranges.copy())
        record_all([(lidar, 0.1 * tick) for lidar in together], [t.copy() for t in truth])
        for a, b in zip(alone, together):
            assert np.array_equal(a.latest.ranges, b.latest.ranges)
            assert a.latest.time == b.latest.time and not b.latest.ranges.flags.writeable


def test_requests_of_many_lidars_are_each_lidars_request():
    from pymunk_bot.sensors.lidar import requests_all

    lidars = _lidars(LIDARS[:3] + [{"beams": 90, "offset": [0.1, -0.05, 0.3]}])
    for k, lidar in enumerate(lidars):  # turned off the grid
        lidar.body.angle = 0.37 + 1.1 * k
    origins, angles, ranges, filters = requests_all(lidars)
    for k, lidar in enumerate(lidars):
        origin, want, max_range, f = lidar.cast_request()
        assert origins[k] == origin and ranges[k] == max_range and filters[k] == f
        assert np.array_equal(angles[k], want)
