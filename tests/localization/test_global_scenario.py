"""scenarios/global_localization.yaml: the robot starts lost and finds itself within 15 s."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot import Simulation
from pymunk_bot.localization.se2 import wrap


def _settling_time(seed: int) -> tuple[float, dict]:
    """Time [s] after which the estimate stays within 0.3 m and 10 deg; the result JSON."""
    sim = Simulation.from_file("global_localization", seed=seed)
    robot = sim.robots["r1"]
    times, good = [], []

    def watch(s) -> None:
        est, truth = robot.localizer.pose, robot.pose
        times.append(s.time)
        good.append(np.hypot(*(est[:2] - truth[:2])) <= 0.3
                    and abs(wrap(est[2] - truth[2])) <= np.deg2rad(10.0))

    sim.observers.append(watch)
    sim.run(sim.config.world.duration)
    bad = np.flatnonzero(~np.asarray(good))
    settled = 0.0 if bad.size == 0 else (times[bad[-1] + 1] if bad[-1] + 1 < len(times)
                                         else float("inf"))
    return settled, sim.result()


def test_one_seed_converges_and_the_final_error_expectation_passes():
    settled, result = _settling_time(4)
    assert settled <= 15.0
    assert result["passed"]
    assert result["robots"]["r1"]["localization"]["final_error"] <= 0.1
    assert any(line.startswith("r1.localization_final_error") for line in result["expectations"])


def test_the_final_error_expectation_fails_when_the_estimate_is_off():
    sim = Simulation.from_file("global_localization", seed=0)
    data = sim.config.model_dump(mode="json", exclude_unset=True)
    data["expect"]["r1"]["localization_final_error"] = 0.3
    data["world"]["duration"] = 0.5
    # Carried 3.5 m away just before the end: the estimate (localized within the first scans,
    # since MCL seeds particles from the scan) is off when the run ends.
    data["events"] = [{"at": 0.45, "robot": "r1", "teleport": [8.5, 3.5, 1.57]}]
    short = Simulation.from_dict(data, seed=0)
    short.run(0.5)
    result = short.result()
    error = result["robots"]["r1"]["localization"]["final_error"]
    assert error > 0.3 and not result["passed"]


@pytest.mark.slow
def test_converges_within_15_s_in_at_least_9_of_10_seeds():
    times = [_settling_time(seed)[0] for seed in range(10)]
    assert sum(t <= 15.0 for t in times) >= 9, times
