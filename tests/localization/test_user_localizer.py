"""A user's own localizer class (examples/my_localizer.py) runs through the same seam."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root, for examples/

from examples.my_localizer import GyroOdometry  # noqa: E402
from pymunk_bot import Simulation  # noqa: E402
from bench.localization_worlds import OFFICE_ROUTE, office_scenario  # noqa: E402
from pymunk_bot.localization import Localizer  # noqa: E402
from pymunk_bot.localization.trial import make_context, run_trial  # noqa: E402


def test_gyro_steadied_odometry_beats_odometry_alone():
    scenario = office_scenario(seed=2)
    scenario["robots"][0]["imu"] = {"gyro_noise_std": 0.002}
    sim = Simulation.from_dict(scenario)
    localizer = GyroOdometry(make_context(sim, "r1", 2, None), gain=0.98)
    assert isinstance(localizer, Localizer)
    trial = run_trial(sim, localizer, OFFICE_ROUTE[:6], 30.0, drive_on="truth")
    _, truth, estimate = trial.arrays()
    mine = np.hypot(*(estimate[-1, :2] - truth[-1, :2]))
    odometry = np.hypot(*(sim.robots["r1"].odometry.pose[:2] - truth[-1, :2]))
    assert mine < 0.3 * odometry
    assert np.all(np.diff(np.trace(np.asarray(trial.covariance), axis1=1, axis2=2)) >= 0)
