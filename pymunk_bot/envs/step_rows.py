"""The navigation task's step arithmetic over rows, compiled: one pass for one robot or many.

What :class:`~pymunk_bot.envs.task.RewardWeights` documents, robot by robot, in the order of
its terms (so the floats are those of the same sum written with numpy arrays); numpy's
per-call cost, ~1 us an operation, was most of a single env's reward.
"""
from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def step_rows(elapsed: float, terminate_on_collision: bool, weights: np.ndarray,
              distance: np.ndarray, collisions: np.ndarray, before: np.ndarray,
              touching: np.ndarray, ranges: np.ndarray, radius: np.ndarray,
              reached: np.ndarray, rewards: np.ndarray, new_collisions: np.ndarray,
              contact_time: np.ndarray, clearance: np.ndarray, success: np.ndarray,
              terminated: np.ndarray) -> None:
    """Row i: a robot after a control step of ``elapsed`` [s]: its distance to the goal [m],
    contact episodes, ``before`` the step (distance [m], contact episodes, contact time [s],
    contact episodes at the start), whether it touches something now, its LiDAR ranges [m]
    and radius [m], whether it reached its goal. ``weights``: progress, contact, collision,
    clearance, clearance margin [m], time, success. Writes its reward, new contact episodes,
    contact time [s] so far, clearance [m], contact-free arrival and whether the episode ends."""
    progress_w, contact_w, collision_w, clearance_w, margin, time_w, success_w = weights
    for i in range(distance.shape[0]):
        new = collisions[i] - np.int64(before[i, 1])
        contact = elapsed if (new > 0 or touching[i]) else 0.0
        nearest = ranges[i, 0]
        for j in range(1, ranges.shape[1]):
            if ranges[i, j] < nearest:
                nearest = ranges[i, j]
        gap = nearest - radius[i]
        time_in_contact = before[i, 2] + contact
        arrived = reached[i] and time_in_contact == 0.0 and collisions[i] == before[i, 3]
        crowding = min(1.0, max(0.0, 1.0 - gap / margin))
        rewards[i] = (progress_w * (before[i, 0] - distance[i]) + collision_w * new
                      + contact_w * contact + clearance_w * elapsed * crowding
                      + time_w * elapsed + success_w * arrived)
        new_collisions[i] = new
        contact_time[i] = time_in_contact
        clearance[i] = gap
        success[i] = arrived
        terminated[i] = reached[i] or (terminate_on_collision and contact > 0.0)
