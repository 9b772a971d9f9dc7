"""A user's own localizer: odometry whose heading is steadied by the IMU's gyro.

Wheel odometry turns wrongly when the track width or wheel radii are off (a systematic error
that grows with every turn); a gyro measures the turn itself but its bias drifts slowly. A
complementary filter takes the turn per tick mostly from the gyro (``gain``) and the rest from
the wheels, and moves the robot by the wheels' distance along that heading.

Run it:  python examples/my_localizer.py
In a scenario (once the core loads Python localizers, like Python controllers):
    localization: {type: python, class_path: examples.my_localizer:GyroOdometry, params: {gain: 0.98}}
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.localization import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.localization.se2 import between, wrap


class GyroOdometry(Localizer):
    """Complementary filter: heading from gyro (weight ``gain``) and wheels, distance from wheels."""

    def __init__(self, context: LocalizerContext, gain: float = 0.98,
                 distance_noise: float = 0.01) -> None:
        if not 0.0 <= gain <= 1.0:
            raise ValueError(f"gain must be in [0, 1] (got {gain})")
        super().__init__({"gain": gain}, context)
        self.gain = gain
        self.distance_noise = distance_noise  # [m/sqrt(m)] for the covariance
        self._odom: np.ndarray | None = None
        self._time: float | None = None

    def update(self, inputs: LocalizerInputs) -> None:
        odom = np.asarray(inputs.odometry, dtype=float)
        if self._odom is not None:
            step = between(self._odom, odom)  # the wheels' motion this tick, robot frame
            turn = step[2]
            if inputs.imu is not None and self._time is not None:
                gyro_turn = inputs.imu.yaw_rate * (inputs.time - self._time)
                turn = self.gain * gyro_turn + (1.0 - self.gain) * step[2]
            distance = float(np.hypot(step[0], step[1])) * np.sign(step[0] or 1.0)
            heading = self.pose[2] + 0.5 * turn  # move along the mid-tick heading
            self.pose = np.array([self.pose[0] + distance * np.cos(heading),
                                  self.pose[1] + distance * np.sin(heading),
                                  float(wrap(self.pose[2] + turn))])
            grow = self.distance_noise ** 2 * abs(distance)
            self.covariance = self.covariance + np.diag([grow, grow, 0.1 * grow])
        self._odom, self._time = odom, inputs.time


def main() -> None:
    from pymunk_bot import Simulation
    from bench.localization_worlds import OFFICE_ROUTE, office_scenario
    from pymunk_bot.localization.metrics import error_block
    from pymunk_bot.localization.trial import make_context, run_trial

    scenario = office_scenario(seed=1)
    scenario["robots"][0]["imu"] = {"gyro_noise_std": 0.002, "gyro_bias_walk": 0.0005}
    sim = Simulation.from_dict(scenario)
    localizer = GyroOdometry(make_context(sim, "r1", 1, None))
    trial = run_trial(sim, localizer, OFFICE_ROUTE, 90.0, drive_on="truth")
    _, truth, estimate = trial.arrays()
    odometry = sim.robots["r1"].odometry.pose
    print(f"after {trial.sim_time:.0f} s: gyro+odometry error {error_block(truth, estimate)['final_error']:.2f} m, "
          f"odometry alone {np.hypot(*(odometry[:2] - truth[-1, :2])):.2f} m")


if __name__ == "__main__":
    main()
