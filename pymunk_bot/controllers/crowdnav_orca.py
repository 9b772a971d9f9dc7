"""CrowdNav's ORCA robot policy (Chen et al., "Crowd-robot interaction", ICRA 2019; its
baseline, crowd_sim/envs/policy/orca.py of vita-epfl/CrowdNav), written anew on this project's
ORCA (:mod:`pymunk_bot.actors.orca`, van den Berg et al. 2011).

Every control period (CrowdNav's time step, 0.25 s) the robot builds ORCA's half-planes against
the nearest ``max_neighbors`` pedestrians within ``neighbor_distance``, from their true
positions, velocities and radii (the ``crowd_state`` sensor), each radius grown by
``radius_margin`` (its own also by ``safety_space``), taking ``share`` of the avoidance
(0.5: reciprocal, as CrowdNav's, which assumes people do ORCA too). Its own velocity in them is
the velocity it asked for last, as CrowdNav's. It wishes goal - position, capped at its speed
(so it slows within max_speed x 1 s of the goal), and takes the velocity closest to that
inside every half-plane (or, if none is, the one that violates them least). A holonomic
(omni) robot drives that velocity; any other drive turns toward it.

The ``orca`` controller is something else: it sees people only as LiDAR points and takes all
of the avoidance (controllers/orca.py).
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.actors.orca import neighbour_lines
from pymunk_bot.config.controllers import CrowdNavOrcaControllerConfig
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec

HEADING_GAIN = 2.5  # [1/s] a non-holonomic robot's yaw rate per radian of heading error
NO_SENSOR = ("the robot has no crowd_state sensor: crowdnav_orca reads the pedestrians' true "
             "states (add `crowd_state: {}` to the robot)")


class CrowdNavOrcaController(Controller):
    """Reciprocal ORCA among the pedestrians' true states (see the module doc)."""

    config: CrowdNavOrcaControllerConfig

    def __init__(self, config: CrowdNavOrcaControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config, robot)
        self.robot = robot
        self.last = np.zeros(2)  # [m/s] the world-frame velocity asked last

    def velocity(self, xy: np.ndarray, goal: np.ndarray, crowd: object, period: float
                 ) -> np.ndarray:
        """The world-frame velocity [m/s] ORCA chooses at ``xy`` [m] toward ``goal`` [m]
        among ``crowd`` (a :class:`~pymunk_bot.sensors.crowd_state.CrowdState`)."""
        from pymunk_bot.actors.orca_lp import solve_all

        c = self.config
        to_goal = goal - xy
        gap = float(np.hypot(*to_goal))
        pref = to_goal * (self.max_speed / gap) if gap > self.max_speed else to_goal
        positions = np.asarray(getattr(crowd, "positions"), dtype=float).reshape(-1, 2)
        velocities = np.asarray(getattr(crowd, "velocities"), dtype=float).reshape(-1, 2)
        radii = np.asarray(getattr(crowd, "radii"), dtype=float).reshape(-1)
        dist = np.hypot(*(positions - xy).T)
        near = np.argsort(dist, kind="stable")
        near = near[dist[near] <= c.neighbor_distance][:c.max_neighbors]
        if not len(near):
            return pref
        k = len(near)
        q, n = neighbour_lines(
            xy[None], self.last[None],
            np.array([self.robot.radius + c.radius_margin + c.safety_space]),
            positions[near][None], velocities[near][None], (radii[near] + c.radius_margin)[None],
            np.full((1, k), c.share), np.array([c.time_horizon]), period)
        return solve_all(np.ascontiguousarray(q), np.ascontiguousarray(n), np.array([k]),
                         np.array([0]), np.array([self.max_speed]), pref[None])[0]

    def compute(self, obs: Observation) -> Command:
        crowd = obs.extra.get("crowd_state")
        if crowd is None:
            self.status, self.message = "failed", NO_SENSOR
            return STOP
        goal = self.config.goal if self.config.goal is not None else obs.goal
        if goal is None:
            self.status, self.message = "failed", "no goal"
            return STOP
        xy = np.array([float(obs.pose[0]), float(obs.pose[1])])
        target = np.array([float(goal[0]), float(goal[1])])
        self.status = "arrived" if math.hypot(*(target - xy)) <= obs.goal_tolerance \
            else "running"
        wished = self.velocity(xy, target, crowd, 1.0 / self.rate)
        self.last = wished
        theta = float(obs.pose[2])
        cos, sin = math.cos(theta), math.sin(theta)
        vx, vy = float(wished[0]), float(wished[1])
        forward, left = cos * vx + sin * vy, -sin * vx + cos * vy  # body frame
        if self.robot.holonomic:
            return Command(forward, 0.0, left)
        bearing = math.atan2(left, forward)
        speed = math.hypot(vx, vy) * max(math.cos(bearing), 0.0)
        omega = max(-self.robot.max_omega, min(self.robot.max_omega, HEADING_GAIN * bearing))
        return Command(speed, omega)
