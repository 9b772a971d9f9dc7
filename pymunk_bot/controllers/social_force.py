"""A robot driven by the social force model (Helbing & Molnar 1995), the classic crowd-aware
baseline: pulled toward a look-ahead point on its global path (relaxation time tau) and pushed
away from every obstacle point its LiDAR sees, A exp((r - d) / B) along the direction from
the point (d its distance, r the robot's radius plus margin), with a moving point's distance
taken to where it will be after ``anticipation`` seconds if that is nearer, and weighted
less behind the direction of travel (the anisotropy of Helbing, Farkas & Vicsek 2000)."""
from __future__ import annotations

import numpy as np

from pymunk_bot.config.controllers import SocialForceControllerConfig
from pymunk_bot.controllers.crowd_nav import CrowdController


ANISOTROPY = 0.3  # lambda: weight of a point straight behind (1 ahead); Helbing et al. 2000


class SocialForceController(CrowdController):
    """Social force toward the path, away from what the LiDAR sees."""

    config: SocialForceControllerConfig

    def velocity(self, xy: np.ndarray, carrot: np.ndarray, points: np.ndarray,
                 point_velocities: np.ndarray, period: float) -> np.ndarray:
        c = self.config
        e = self.heading_to(xy, carrot)
        force = (self.max_speed * e - self.last) / c.relaxation_time
        if len(points):
            ahead = points + point_velocities * c.anticipation
            rel = np.where((np.hypot(*(xy - ahead).T) < np.hypot(*(xy - points).T))[:, None],
                           xy - ahead, xy - points)
            d = np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 1e-6)
            reach = self.robot.radius + c.margin
            push = c.strength * np.exp((reach - d) / c.range)
            # Anisotropy (Helbing et al. 2000): what lies behind the direction of travel
            # pushes less, lambda + (1 - lambda) (1 + cos phi) / 2.
            cos_phi = -(rel @ e) / d
            push *= ANISOTROPY + (1.0 - ANISOTROPY) * 0.5 * (1.0 + cos_phi)
            force += (push[:, None] * rel / d[:, None]).sum(axis=0)
        return self.last + force * period
