"""When a recorded run has settled, so its video can end (issue 35).

A run has settled when every robot is done (its controller arrived or gave up, or it has none)
and nothing drawn moves (robots, movable obstacles, pedestrians: every pose in the scene) for
:data:`SETTLE_TIME` of simulated time. Nothing would change on screen after that but the clock,
so a recording stops there instead of showing a still picture to the end of the run.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.viewer.scene import Scene

SETTLE_TIME = 1.0  # [s] of simulated time with nothing moving before a video ends
STILL = 1e-4  # [m] (and [rad]) a pose that changed less than this between frames has not moved


def _done(status: str) -> bool:
    return status in ("arrived", "no controller") or status.startswith("failed")


class Settling:
    """Fed every frame's scene, says whether the run has settled (see the module's docstring)."""

    def __init__(self, settle_time: float = SETTLE_TIME) -> None:
        self.settle_time = settle_time  # [s]
        self._poses: np.ndarray | None = None
        self._still_since: float | None = None  # [s] simulated time from which nothing moved

    def settled(self, scene: Scene) -> bool:
        """Whether, at this frame, everything has been done and still for ``settle_time``."""
        # Every shape's pose: fixed ones never change, so any that does has moved.
        poses = np.array([r.pose for r in scene.robots] + [s.pose for s in scene.shapes],
                         dtype=float).reshape(-1, 3)
        moved = (self._poses is None or poses.shape != self._poses.shape
                 or bool(np.any(np.abs(poses - self._poses) > STILL)))
        self._poses = poses
        if moved or not all(_done(r.status) for r in scene.robots):
            self._still_since = None
            return False
        if self._still_since is None:
            self._still_since = scene.time
        return scene.time - self._still_since >= self.settle_time - 1e-9
