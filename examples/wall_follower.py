"""A user's own controller, run from YAML with `controller: {type: python, ...}`.

Run it:  python examples/wall_follower.py   (or: pymunk-bot run examples/wall_follower.yaml,
from the repository root, so that `examples.wall_follower` is importable).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from pymunk_bot.controllers import Controller, Observation, RobotSpec, wheel_speeds


class WallFollower(Controller):
    """Keeps a wall on its right at ``distance`` metres using the LiDAR (P control on range)."""

    rate = 10.0  # [Hz]

    def __init__(self, robot: RobotSpec, distance: float = 0.6, speed: float = 0.4,
                 gain: float = 2.0) -> None:
        super().__init__()
        self.robot = robot
        self.distance = distance  # [m] wanted gap to the wall on the right
        self.speed = speed  # [m/s]
        self.gain = gain  # [rad/s per m]

    def compute(self, obs: Observation) -> tuple[float, float]:
        if obs.scan is None:
            self.status, self.message = "failed", "needs a lidar"
            return 0.0, 0.0
        angles, ranges = np.asarray(obs.scan.angles), np.asarray(obs.scan.ranges)
        right = ranges[np.abs(angles + np.pi / 2) < 0.3].min()
        ahead = ranges[np.abs(angles) < 0.4].min()
        if ahead < self.distance + self.robot.radius:
            return wheel_speeds(0.0, 1.0, self.robot.track_width)  # wall ahead: turn left
        omega = self.gain * (self.distance - right)
        self.message = f"wall at {right:.2f} m"
        return wheel_speeds(self.speed, float(np.clip(omega, -1.5, 1.5)), self.robot.track_width)


def main() -> None:
    import sys

    from pymunk_bot import Simulation

    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root))  # so that `examples.wall_follower` imports from anywhere
    sim = Simulation.from_file(Path(__file__).with_suffix(".yaml"))
    sim.run(sim.config.world.duration)
    result = sim.result()
    for name, r in result["robots"].items():
        print(f"{name}: {r['distance']:.1f} m driven, {r['collisions']} collisions, "
              f"closest {r['min_clearance']:.2f} m ({r['controller_message']})")
    print("PASSED" if result["passed"] else "FAILED")


if __name__ == "__main__":
    main()
