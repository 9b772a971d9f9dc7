"""A robot driven by a LiDAR-based ORCA (van den Berg et al. 2011): the velocity closest to
the one toward its look-ahead point on a global A* path that no obstacle point its LiDAR sees
can collide with within ``time_horizon`` (moving points, at their tracked velocity) or
``obstacle_time_horizon`` (static points). It sees people only as LiDAR points (the nearest
return in each of 36 sectors within 4 m), grows its radius by ``margin`` and takes all of the
avoidance: the people it meets may not reciprocate.

This is not CrowdNav's ORCA baseline: that one reads every human's true position, velocity and
radius and assumes they reciprocate (``crowdnav_orca``, controllers/crowdnav_orca.py)."""
from __future__ import annotations

import numpy as np

from pymunk_bot.actors.orca import neighbour_lines
from pymunk_bot.config.controllers import OrcaControllerConfig
from pymunk_bot.controllers.crowd_nav import CrowdController

MOVING = 0.05  # [m/s] points faster than this are moving obstacles (soft constraints)


class OrcaController(CrowdController):
    """ORCA toward the path, around what the LiDAR sees."""

    config: OrcaControllerConfig

    def velocity(self, xy: np.ndarray, carrot: np.ndarray, points: np.ndarray,
                 point_velocities: np.ndarray, period: float) -> np.ndarray:
        from pymunk_bot.actors.orca_lp import solve_all

        c = self.config
        pref = self.heading_to(xy, carrot) * self.max_speed
        radius = np.array([self.robot.radius + c.margin])
        moving = np.hypot(*point_velocities.T) > MOVING if len(points) else np.zeros(0, bool)
        lines_q, lines_n = [], []
        for mask, horizon in ((~moving, c.obstacle_time_horizon), (moving, c.time_horizon)):
            if mask.any():
                q, n = neighbour_lines(xy[None], self.last[None], radius, points[mask][None],
                                       point_velocities[mask][None],
                                       np.zeros((1, int(mask.sum()))),
                                       np.ones((1, int(mask.sum()))), np.array([horizon]),
                                       period)
                lines_q.append(q[0])
                lines_n.append(n[0])
        if not lines_q:
            return pref
        q = np.ascontiguousarray(np.concatenate(lines_q)[None])
        n = np.ascontiguousarray(np.concatenate(lines_n)[None])
        # Static points first; none is hard: when they leave no room (a doorway, a crowd at a
        # wall), the velocity that violates the half-planes least is taken.
        return solve_all(q, n, np.array([q.shape[1]]), np.array([0]),
                         np.array([self.max_speed]), pref[None])[0]
