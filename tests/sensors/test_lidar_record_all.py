"""Many scans requested and stored as rows (LidarRows) are exactly the scans each LiDAR takes
and stores alone."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot.sensors.lidar_rows import LidarRows
from pymunk_bot.engine.simulation import Simulation

LIDARS = [{"beams": 90, "noise_std": 0.01},
          {"beams": 90, "noise_std": 0.05, "dropout": 0.2, "min_range": 0.5, "max_range": 4.0},
          {"beams": 90},  # exact ranges
          {"beams": 90, "dropout": 0.3},  # dropout without noise
          {"beams": 90, "noise_std": 0.002, "max_range": 12.0},
          {"beams": 90, "min_range": 0.5, "max_range": 6.0}]  # exact, other limits
ANOTHER_COUNT = {"beams": 45, "noise_std": 0.01}  # mixed beam counts: stored one by one


def _lidars(lidars):
    return _scene(lidars)[1]


def _scene(lidars):
    robots = [{"name": f"r{i}", "pose": [1.0 + 1.5 * i, 1.0, 0.0], "lidar": lidar}
              for i, lidar in enumerate(lidars)]
    sim = Simulation.from_dict({"name": "scans", "world": {"size": [12.0, 3.0]},
                                "robots": robots}, seed=4)
    return sim, [robot.lidar for robot in sim.robots.values()]


@pytest.mark.parametrize("lidars", [LIDARS, LIDARS + [ANOTHER_COUNT]])
def test_scans_stored_together_equal_scans_stored_alone(lidars):
    alone, together = _lidars(lidars), _lidars(lidars)
    rows = LidarRows(together, range(len(together)))
    rng = np.random.default_rng(0)
    for tick in range(5):  # the random streams stay in step scan after scan
        truth = [rng.uniform(0.0, 13.0, lidar.config.beams) for lidar in alone]
        truth[0][:5] = [0.0, 0.3, 4.0, 8.0, 13.0]  # at and beyond the limits
        for lidar, ranges in zip(alone, truth):
            lidar.record(0.1 * tick, ranges.copy())
        rows.store(range(len(together)), [0.1 * tick] * len(together), [t.copy() for t in truth])
        for a, b in zip(alone, together):
            assert np.array_equal(a.latest.ranges, b.latest.ranges)
            assert a.latest.time == b.latest.time and not b.latest.ranges.flags.writeable


@pytest.mark.parametrize("extra", [{"beams": 90, "offset": [0.1, -0.05, 0.3]},
                                   {"beams": 45, "offset": [0.0, 0.0, -0.2]}])
def test_requests_of_many_lidars_are_each_lidars_request(extra):
    sim, lidars = _scene(LIDARS[:3] + [extra])
    for k, lidar in enumerate(lidars):  # turned off the grid
        lidar.body.angle = 0.37 + 1.1 * k
        lidar.body.position = (1.1 + 1.5 * k + 1e-3 * k, 0.9 + 0.01 * k)
    poses = sim.built.propulsion.pose_array()  # one pymunk.batch read
    origins, angles, ranges, filters = LidarRows(lidars, range(len(lidars))).requests(
        [0, 1, 2, 3], poses)
    for k, lidar in enumerate(lidars):
        origin, want, max_range, f = lidar.cast_request()
        assert tuple(origins[k]) == origin and ranges[k] == max_range and filters[k] == f
        assert np.array_equal(angles[k], want)
