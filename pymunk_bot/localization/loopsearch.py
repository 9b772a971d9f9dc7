"""Where a loop may close: the keyframes the robot could be near, given how unsure the chain is.

SLAM's front end chains keyframes by scan matches, each with a covariance. Drift along the
chain grows with it: every step adds its own position error, and its heading error swings
everything after it about the place it was made. So the pose of keyframe j relative to an
earlier keyframe i has (world frame, cross terms left out, linearised)

    position covariance  sum_{k=i+1..j} [P_k + h_k (|d_k|^2 I - d_k d_k^T)],  d_k = p_j - p_k
    heading variance     sum_{k=i+1..j} h_k

with P_k (2x2) and h_k the position covariance and heading variance of step k. The sums
expand into prefix sums of P_k, h_k, h_k p_k and h_k p_k p_k^T, so the covariance of the
newest keyframe relative to *every* earlier one is a few vectorised operations
(:meth:`ChainUncertainty.relative`). A keyframe is a loop candidate when it was passed at
least ``min_travel`` of driving ago and the newest keyframe could be within ``radius`` of it
at ``gate`` standard deviations of that covariance (:func:`candidates`).
"""
from __future__ import annotations

import numpy as np

INITIAL_CAPACITY = 256  # keyframes; the arrays double when full


class ChainUncertainty:
    """Prefix sums of the keyframe chain's step covariances (module docstring)."""

    def __init__(self) -> None:
        self.count = 0
        self._steps = np.zeros((INITIAL_CAPACITY, 3, 3))  # each step's covariance, world frame
        self._positions = np.zeros((INITIAL_CAPACITY, 2))  # [m] each keyframe's position
        # prefix sums up to and including each keyframe: P (2x2), h, h p (2), h p p^T (2x2)
        self._p = np.zeros((INITIAL_CAPACITY, 2, 2))
        self._h0 = np.zeros(INITIAL_CAPACITY)
        self._h1 = np.zeros((INITIAL_CAPACITY, 2))
        self._h2 = np.zeros((INITIAL_CAPACITY, 2, 2))

    def add(self, position: np.ndarray, step_covariance: np.ndarray) -> None:
        """The next keyframe at ``position`` [m] (x, y), reached by a step of covariance
        ``step_covariance`` (3x3, world frame; zeros for the first keyframe)."""
        if self.count == self._h0.size:
            self._grow()
        k = self.count
        self._steps[k] = step_covariance
        self._positions[k] = np.asarray(position, dtype=float)[:2]
        self.count += 1
        self._accumulate(k)

    def move(self, positions: np.ndarray) -> None:
        """The keyframes moved (the graph was optimized): positions (count, 2+) [m]."""
        n = self.count
        pos = self._positions[:n] = np.asarray(positions, dtype=float)[:n, :2]
        h = self._steps[:n, 2, 2]
        self._h1[:n] = np.cumsum(h[:, None] * pos, axis=0)
        self._h2[:n] = np.cumsum(h[:, None, None] * pos[:, :, None] * pos[:, None, :], axis=0)

    def relative(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Covariance of keyframe ``j`` relative to each keyframe i < j: position (j, 2, 2)
        [m^2] and heading (j,) [rad^2], both world frame."""
        if j <= 0:
            return np.zeros((0, 2, 2)), np.zeros(0)
        # sums over k in (i, j] = prefix[j] - prefix[i]
        p = self._p[j] - self._p[:j]
        h0 = self._h0[j] - self._h0[:j]
        h1 = self._h1[j] - self._h1[:j]
        h2 = self._h2[j] - self._h2[:j]
        pj = self._positions[j]
        # sum h_k d_k d_k^T with d_k = p_j - p_k
        ddt = (h0[:, None, None] * np.outer(pj, pj) - pj[None, :, None] * h1[:, None, :]
               - h1[:, :, None] * pj[None, None, :] + h2)
        spread = np.trace(ddt, axis1=1, axis2=2)[:, None, None] * np.eye(2) - ddt
        return p + spread, h0

    def _accumulate(self, k: int) -> None:
        cov, pos = self._steps[k], self._positions[k]
        h = float(cov[2, 2])
        before = (self._p[k - 1], self._h0[k - 1], self._h1[k - 1], self._h2[k - 1]) if k else (
            np.zeros((2, 2)), 0.0, np.zeros(2), np.zeros((2, 2)))
        self._p[k] = before[0] + cov[:2, :2]
        self._h0[k] = before[1] + h
        self._h1[k] = before[2] + h * pos
        self._h2[k] = before[3] + h * np.outer(pos, pos)

    def _grow(self) -> None:
        for name in ("_steps", "_positions", "_p", "_h0", "_h1", "_h2"):
            old = getattr(self, name)
            new = np.zeros((2 * old.shape[0],) + old.shape[1:])
            new[:old.shape[0]] = old
            setattr(self, name, new)


def candidates(positions: np.ndarray, travel: np.ndarray, position_covariance: np.ndarray,
               radius: float, min_travel: float, gate: float,
               max_uncertainty: float) -> np.ndarray:
    """Indices of the keyframes i < j (j = len(travel) - 1, the newest) the newest could be
    within ``radius`` [m] of: |p_j - p_i| <= radius + gate * sigma_i, where sigma_i [m] is the
    largest standard deviation of ``position_covariance[i]`` (relative, (j, 2, 2)) capped at
    ``max_uncertainty`` [m], and only those driven past at least ``min_travel`` [m] ago.
    Nearest first."""
    j = travel.shape[0] - 1
    if j <= 0:
        return np.zeros(0, dtype=np.intp)
    far_back = np.flatnonzero(travel[j] - travel[:j] >= min_travel)
    if far_back.size == 0:
        return far_back
    cov = position_covariance[far_back]
    # the largest eigenvalue of each symmetric 2x2 block, in closed form
    half_trace = 0.5 * (cov[:, 0, 0] + cov[:, 1, 1])
    half_diff = 0.5 * (cov[:, 0, 0] - cov[:, 1, 1])
    largest = half_trace + np.sqrt(half_diff ** 2 + cov[:, 0, 1] ** 2)
    sigma = np.minimum(np.sqrt(np.maximum(largest, 0.0)), max_uncertainty)
    dist = np.hypot(*(positions[far_back, :2] - positions[j, :2]).T)
    near = dist <= radius + gate * sigma
    return far_back[near][np.argsort(dist[near], kind="stable")]
