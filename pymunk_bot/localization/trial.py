"""Run a localizer inside a simulation exactly as the core does, and score it.

After every ``sim.step()`` the localizer gets ``LocalizerInputs(time, odometry, scan)``; the
robot is driven along a route by pure pursuit on the *estimate* (what the controller sees when
a localizer is configured), 10 times a second. Truth and estimate are recorded every step.
Used by the tests (tests/localization/) and the bench (benchmarks/localization.py).
"""
from __future__ import annotations

import time as wallclock
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from pymunk_bot.config.controllers import PursuitConfig
from pymunk_bot.controllers.waypoints import PathFollower, pursuit_gains
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.localization.base import Localizer, LocalizerContext, LocalizerInputs
from pymunk_bot.localization.metrics import error_block

CONTROL_RATE = 10.0  # [Hz]


@dataclass
class Trial:
    """What one run recorded: times [s], true and estimated poses (n, 3), covariances (n, 3, 3)."""

    times: list = field(default_factory=list)
    truth: list = field(default_factory=list)
    estimate: list = field(default_factory=list)
    covariance: list = field(default_factory=list)
    wall_time: float = 0.0  # [s] spent in the localizer's update
    sim_time: float = 0.0  # [s]
    collisions: int = 0

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return np.asarray(self.times), np.asarray(self.truth), np.asarray(self.estimate)

    def errors(self) -> dict[str, float]:
        """The result JSON's localization block for this run."""
        _, truth, estimate = self.arrays()
        return error_block(truth, estimate)


def make_context(sim, robot_name: str, seed: int, grid: OccupancyGrid | None) -> LocalizerContext:
    """The context the core builds: spec, true start pose, own RNG stream, arena, map, mount."""
    robot = sim.robots[robot_name]
    lidar = robot.sensor("lidar")
    offset = lidar.offset if lidar is not None else (0.0, 0.0, 0.0)
    return LocalizerContext(robot=robot.spec, start_pose=robot.pose.copy(),
                            rng=np.random.default_rng([seed, 11]),
                            arena=(sim.world.width, sim.world.height), map=grid,
                            lidar_offset=offset, origin=tuple(sim.world.extent[:2]))


def run_trial(sim, localizer: Localizer, route: list[tuple[float, float]], max_time: float,
              robot_name: str = "r1", speed: float = 0.5, drive_on: str = "estimate",
              on_step: Callable | None = None) -> Trial:
    """Drive ``route`` (pure pursuit on the estimate or the truth) until its end or ``max_time``."""
    robot = sim.robots[robot_name]
    gains = pursuit_gains(PursuitConfig(), robot.spec, speed)
    follower: PathFollower | None = None
    trial = Trial()
    next_control = 0.0
    done = False

    def feed() -> None:
        lidar, imu = robot.sensor("lidar"), robot.sensor("imu")
        scan = lidar.latest if lidar is not None else None
        imu = imu.reading if imu is not None else None
        started = wallclock.perf_counter()
        localizer.update(LocalizerInputs(time=sim.time, odometry=robot.odometry.pose, scan=scan,
                                         imu=imu))
        trial.wall_time += wallclock.perf_counter() - started
        trial.times.append(sim.time)
        trial.truth.append(robot.pose.copy())
        trial.estimate.append(np.array(localizer.pose, dtype=float))
        trial.covariance.append(np.array(localizer.covariance, dtype=float))

    feed()  # the t = 0 scan
    while sim.time < max_time - 1e-9 and not done:
        if sim.time + 1e-9 >= next_control:
            next_control += 1.0 / CONTROL_RATE
            pose = localizer.pose if drive_on == "estimate" else robot.pose
            if follower is None:
                follower = PathFollower([tuple(pose[:2])] + list(route), False, gains, 0.3)
            v, omega, left = follower.command(pose)
            if left < 0.1 and follower.tracker.remaining() < 0.2:
                v, omega, done = 0.0, 0.0, True
            robot.set_velocity(v, omega)
        sim.step()
        feed()
        if on_step is not None:
            on_step(sim, localizer)
    trial.sim_time = sim.time
    trial.collisions = robot.collisions
    return trial
