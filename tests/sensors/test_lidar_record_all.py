"""Many scans stored at once (record_all) are exactly the scans each LiDAR stores alone."""
from __future__ import annotations

import numpy as np

from pymunk_bot.sensors.lidar import record_all
from pymunk_bot.sim import Simulation

LIDARS = [{"beams": 90, "noise_std": 0.01},
          {"beams": 90, "noise_std": 0.05, "dropout": 0.2, "min_range": 0.5, "max_range": 4.0},
          {"beams": 90},  # exact ranges
          {"beams": 90, "dropout": 0.3},  # dropout without noise
          {"beams": 90, "noise_std": 0.002, "max_range": 12.0},
          {"beams": 45, "noise_std": 0.01}]  # another beam count


def _lidars():
    robots = [{"name": f"r{i}", "pose": [1.0 + 1.5 * i, 1.0, 0.0], "lidar": lidar}
              for i, lidar in enumerate(LIDARS)]
    sim = Simulation.from_dict({"name": "scans", "world": {"size": [10.0, 3.0]},
                                "robots": robots}, seed=4)
    return [robot.lidar for robot in sim.robots.values()]


def test_scans_stored_together_equal_scans_stored_alone():
    alone, together = _lidars(), _lidars()
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
