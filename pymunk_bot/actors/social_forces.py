"""The walkers' repulsion from one another and from robots (Helbing & Molnar 1995's elliptical
potential, with keep-right; see :mod:`.pedestrians` for the model), compiled with numba."""
from __future__ import annotations

import math

import numba
import numpy as np

from pymunk_bot.actors.clearance import CONTACT_MARGIN, record

STEP_TIME = 2.0  # [s] Delta t of the elliptical potential (Helbing & Molnar 1995)
SIGHT_COS = math.cos(math.radians(100.0))  # half the field of view
SIGHT_WEIGHT = 0.5  # weight of forces from outside the field of view
# People facing each other head-on both step to their right: without this a walker and a robot
# on one line balance forever. Part of a repulsion from ahead is turned to the walker's right.
KEEP_RIGHT = 0.5
# The 1995 paper measures distances between centres, for people of about this radius [m]; a
# bigger body (a robot, a large walker) is felt from farther by its excess size.
NOMINAL_RADIUS = 0.25
SOCIAL_CUTOFF = 3.0  # [m] beyond their step |s| plus this, others' forces are left out (< 1 %)


@numba.njit(cache=True, nogil=True)
def social_forces(pos: np.ndarray, vel: np.ndarray, goal: np.ndarray, wish: np.ndarray,
                  pull: np.ndarray, tau: np.ndarray, radius: np.ndarray, opos: np.ndarray,
                  ovel: np.ndarray, orad: np.ndarray, v0: np.ndarray, sigma: np.ndarray,
                  reacts: np.ndarray, force: np.ndarray, pref: np.ndarray,
                  step_reach: np.ndarray, near: np.ndarray, count: np.ndarray) -> None:
    """The driving and social forces per unit mass [m/s^2] on each of the n walkers at
    ``pos`` with ``vel``, ``radius``, into ``force`` (n, 2), and their wished velocities
    [m/s] into ``pref`` (n, 2): ``wish`` [m/s] toward ``goal`` plus ``pull`` [m/s]. The others
    are ``opos``, ``ovel``, ``orad``: the walkers first, then robots, which walkers that do not
    ``react`` ignore.

    Driving: (pref - v) / tau. From each other b within its step |s| + SOCIAL_CUTOFF + its
    radius: V0 / sigma exp(-gap / sigma) along grad b, b the semi-minor axis of the ellipse
    through the walker with foci at the other and its next step (2b = sqrt((|r| + |r - s|)^2 -
    |s|^2), r from the other to the walker, s = v_b STEP_TIME), gap = b less both bodies' size
    beyond NOMINAL_RADIUS; weighted SIGHT_WEIGHT from behind (outside the field of view around
    the goal direction e). Then KEEP_RIGHT of the social force's part against e is turned to
    the walker's right.

    Every other walker whose room (:mod:`.clearance`) is within twice the walker's
    ``step_reach`` [m] (its travel in a step: both may close the gap) is recorded into
    ``near`` and ``count`` (a :class:`.clearance.Clearances`' arrays), afresh."""
    n = len(pos)
    for i in range(n):
        count[i] = 0  # this tick's record starts here (the wall forces' follow)
        ex, ey = goal[i, 0] - pos[i, 0], goal[i, 1] - pos[i, 1]
        norm = max(math.sqrt(ex * ex + ey * ey), 1e-9)
        ex, ey = ex / norm, ey / norm
        px, py = wish[i] * ex + pull[i, 0], wish[i] * ey + pull[i, 1]
        pref[i, 0], pref[i, 1] = px, py
        fx, fy = 0.0, 0.0
        for j in range(len(opos)):
            if j == i or (j >= n and not reacts[i]):
                continue
            sx, sy = ovel[j, 0] * STEP_TIME, ovel[j, 1] * STEP_TIME
            rx, ry = pos[i, 0] - opos[j, 0], pos[i, 1] - opos[j, 1]
            reach = math.sqrt(sx * sx + sy * sy) + SOCIAL_CUTOFF + orad[j]
            if rx * rx + ry * ry >= reach * reach:
                continue
            qx, qy = rx - sx, ry - sy
            rn = max(math.sqrt(rx * rx + ry * ry), 1e-9)
            if j < n and rn - radius[i] - orad[j] - CONTACT_MARGIN < 2.0 * step_reach[i]:
                record(near, count, i, rn - radius[i] - orad[j], -rx / rn, -ry / rn, j)
            qn = max(math.sqrt(qx * qx + qy * qy), 1e-9)
            two_b = math.sqrt(max((rn + qn) ** 2 - (sx * sx + sy * sy), 1e-12))
            scale = (rn + qn) / (2.0 * two_b)
            gap = max(0.5 * two_b - (radius[i] + orad[j] - 2.0 * NOMINAL_RADIUS), 0.0)
            magnitude = v0[i] / sigma[i] * math.exp(-gap / sigma[i])
            if -(rx * ex + ry * ey) / rn < SIGHT_COS:
                magnitude *= SIGHT_WEIGHT
            fx += magnitude * scale * (rx / rn + qx / qn)
            fy += magnitude * scale * (ry / rn + qy / qn)
        against = max(-(fx * ex + fy * ey), 0.0)  # the part that holds us back
        force[i, 0] = (px - vel[i, 0]) / tau[i] + fx + KEEP_RIGHT * against * ey
        force[i, 1] = (py - vel[i, 1]) / tau[i] + fy - KEEP_RIGHT * against * ex


@numba.njit(cache=True, nogil=True)
def cap_speeds(velocity: np.ndarray, cap: np.ndarray) -> None:
    """Scale each row of ``velocity`` (n, 2) [m/s] down to at most ``cap`` [m/s], in place."""
    for i in range(len(velocity)):
        speed = math.sqrt(velocity[i, 0] ** 2 + velocity[i, 1] ** 2)
        if speed > cap[i]:
            velocity[i, 0] *= cap[i] / speed
            velocity[i, 1] *= cap[i] / speed


@numba.njit(cache=True, nogil=True)
def arrivals(goal: np.ndarray, pos: np.ndarray, tolerance: np.ndarray,
             done: np.ndarray) -> np.ndarray:
    """Indices of the walkers at ``pos`` within ``tolerance`` [m] of their ``goal`` [m] and
    not ``done``."""
    out = np.empty(len(pos), dtype=np.int64)
    count = 0
    for i in range(len(pos)):
        dx, dy = goal[i, 0] - pos[i, 0], goal[i, 1] - pos[i, 1]
        if not done[i] and dx * dx + dy * dy <= tolerance[i] * tolerance[i]:
            out[count] = i
            count += 1
    return out[:count]
