"""The odometry motion model (Thrun et al., Probabilistic Robotics, table 5.6), as ROS AMCL has it.

Between two filter updates odometry reports a motion from ``old`` to ``new`` (odometry frame).
The "diff" model splits it into a turn ``rot1`` toward the direction of travel, a straight
``trans`` and a final turn ``rot2``, and samples each with a standard deviation of

    rot1, rot2:  sqrt(alpha1 * rot^2 + alpha2 * trans^2)
    trans:       sqrt(alpha3 * trans^2 + alpha4 * (rot1^2 + rot2^2))

so ``alpha1`` is rotation noise from rotation, ``alpha2`` rotation noise from translation,
``alpha3`` translation noise from translation and ``alpha4`` translation noise from rotation
(all dimensionless variance ratios). As in AMCL, a turn is measured against the nearer of
driving forwards or backwards, so reversing is not mistaken for a half turn. The "omni" model
adds a sideways ``strafe`` whose noise is ``alpha5`` (strafe from translation).
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.localization.se2 import wrap

MIN_TRANS_FOR_HEADING = 0.01  # [m]; below this the direction of travel is meaningless (AMCL)


def _turn_noise(angle: float) -> float:
    """|angle| against forward or backward travel, whichever is closer [rad]."""
    return min(abs(float(wrap(angle))), abs(float(wrap(angle - np.pi))))


def sample_motion(particles: np.ndarray, old: np.ndarray, new: np.ndarray,
                  alphas: tuple[float, float, float, float, float], rng: np.random.Generator,
                  model: str = "diff") -> np.ndarray:
    """Move each particle (n, 3) by the odometry motion old -> new with sampled noise."""
    dx, dy = float(new[0] - old[0]), float(new[1] - old[1])
    dtheta = float(wrap(new[2] - old[2]))
    trans = float(np.hypot(dx, dy))
    a1, a2, a3, a4, a5 = alphas
    n = particles.shape[0]
    out = particles.copy()
    if model == "omni":
        rot = dtheta
        bearing = wrap(np.arctan2(dy, dx) - old[2]) + particles[:, 2]
        trans_hat = trans + rng.normal(0.0, np.sqrt(a3 * trans**2 + a1 * rot**2), n)
        rot_hat = rot + rng.normal(0.0, np.sqrt(a4 * rot**2 + a2 * trans**2), n)
        strafe_hat = rng.normal(0.0, np.sqrt(a1 * rot**2 + a5 * trans**2), n)
        c, s = np.cos(bearing), np.sin(bearing)
        out[:, 0] += trans_hat * c + strafe_hat * s
        out[:, 1] += trans_hat * s - strafe_hat * c
        out[:, 2] = wrap(out[:, 2] + rot_hat)
        return out
    rot1 = 0.0 if trans < MIN_TRANS_FOR_HEADING else float(wrap(np.arctan2(dy, dx) - old[2]))
    rot2 = float(wrap(dtheta - rot1))
    n1, n2 = _turn_noise(rot1), _turn_noise(rot2)
    rot1_hat = rot1 - rng.normal(0.0, np.sqrt(a1 * n1**2 + a2 * trans**2), n)
    trans_hat = trans - rng.normal(0.0, np.sqrt(a3 * trans**2 + a4 * (n1**2 + n2**2)), n)
    rot2_hat = rot2 - rng.normal(0.0, np.sqrt(a1 * n2**2 + a2 * trans**2), n)
    heading = particles[:, 2] + rot1_hat
    out[:, 0] += trans_hat * np.cos(heading)
    out[:, 1] += trans_hat * np.sin(heading)
    out[:, 2] = wrap(particles[:, 2] + rot1_hat + rot2_hat)
    return out
