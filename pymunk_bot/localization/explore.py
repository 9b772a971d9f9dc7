"""Where a lost robot should drive to tell its hypotheses apart (active localization).

A particle filter with two hypotheses that both explain every scan (a warehouse aisle and the
same aisle seen turned 180 deg, or a look-alike aisle elsewhere) learns nothing from a robot
that turns on the spot or drives along the aisle: each hypothesis predicts the same scans.
It learns where they predict different ones. For each candidate heading (robot frame), every
hypothesis (a cluster of particles, its mean pose) is moved ``step`` along that heading on the
map (less where the map puts an obstacle in its way) and the scan it would see there is
predicted by tracing the map; the heading whose predicted scans differ most (the weighted
variance of the predicted ranges, summed over beams) is where to drive. Only headings where
the robot's own scan shows a free corridor count, so the choice never leads into something
the LiDAR sees (after Burgard, Fox and Thrun's active Markov localization, 1997, with the
expected entropy replaced by this spread of predicted ranges).
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.localization.se2 import wrap

EXPLORE_HEADINGS = 36  # candidate headings, every 10 deg (robot frame)
EXPLORE_BEAMS = 24  # predicted ranges per hypothesis and heading
EXPLORE_STEP = 1.5  # [m] how far ahead each hypothesis is moved before it is compared
MAX_TRACE_STEPS = 200  # sphere-tracing iterations per ray (bounds the cost)
# [m^2] least disagreement worth driving for: summed over EXPLORE_BEAMS, ranges differing by
# 0.15 m rms (a few sigma_hit-wide misfits); below it the hypotheses agree wherever one goes.
MIN_DISAGREEMENT = EXPLORE_BEAMS * 0.15 ** 2
EXPLORE_RETRY = 1.0  # [s] between searches for a heading while none is worth driving
# [s] longest a chosen heading is held: turning to it (up to 6.3 s at 0.5 rad/s) and driving
# EXPLORE_STEP (5 s at 0.3 m/s), with margin
EXPLORE_PATIENCE = 15.0


def trace(field: LikelihoodField, origin: np.ndarray, heading: np.ndarray, max_range: float,
          tolerance: float | None = None) -> np.ndarray:
    """Ranges [m] of rays from ``origin`` (n, 2) at world ``heading`` (n, m) to the map's
    obstacles, capped at ``max_range``, by sphere tracing the distance field (steps of the
    clearance, at least ``tolerance``: a ray stops within it of a surface; default half a
    field cell; a coarser one is cheaper where rays graze a wall)."""
    eps = 2.0 * tolerance if tolerance is not None else field.resolution
    direction = np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    t = np.zeros(heading.shape)
    active = np.ones(heading.shape, dtype=bool)
    for _ in range(MAX_TRACE_STEPS):
        if not active.any():
            break
        pts = origin[:, None, :] + t[..., None] * direction
        d = field.clearance(pts)
        hit = d < 0.5 * eps
        active &= ~hit & (t < max_range)
        t = np.where(active, t + np.maximum(d, 0.5 * eps), t)
    return np.minimum(t, max_range)


def corridor_lengths(points: np.ndarray, headings: np.ndarray, half_width: float, cap: float) -> np.ndarray:
    """[m] Per heading (rad, robot frame), how far a corridor of ``half_width`` either side
    runs from the robot's centre before one of the scan's end ``points`` (m, 2, robot frame);
    ``cap`` where none does."""
    c, s = np.cos(headings)[:, None], np.sin(headings)[:, None]
    along = c * points[:, 0] + s * points[:, 1]
    across = -s * points[:, 0] + c * points[:, 1]
    blocking = (along > 0.0) & (np.abs(across) < half_width)
    return np.where(blocking, along, cap).min(axis=1, initial=cap)


def disagreement(field: LikelihoodField, hypotheses: np.ndarray, weights: np.ndarray,
                 headings: np.ndarray, max_range: float, robot_radius: float,
                 step: float = EXPLORE_STEP, beams: int = EXPLORE_BEAMS) -> np.ndarray:
    """Per heading (robot frame, rad), the weighted variance over ``hypotheses`` (k, 3, world
    poses, ``weights`` summing to 1) of the ranges each would see after driving ``step`` that
    way, summed over ``beams`` evenly spread beams [m^2]."""
    k, h = hypotheses.shape[0], headings.size
    world = hypotheses[:, None, 2] + headings[None, :]  # (k, h) heading of the move
    origin = np.repeat(hypotheses[:, :2], h, axis=0)  # (k*h, 2)
    free = trace(field, origin, world.reshape(-1, 1), step + robot_radius)[:, 0]
    move = np.clip(free - robot_radius, 0.0, step).reshape(k, h)
    ahead = hypotheses[:, None, :2] + move[..., None] * np.stack([np.cos(world), np.sin(world)], -1)
    angles = np.linspace(-np.pi, np.pi, beams, endpoint=False)
    ranges = trace(field, ahead.reshape(-1, 2), wrap(world.reshape(-1, 1) + angles[None, :]),
                   max_range).reshape(k, h, beams)
    mean = np.einsum("k,khb->hb", weights, ranges)
    spread = np.einsum("k,khb->hb", weights, (ranges - mean) ** 2)
    return spread.sum(axis=1)


def explore_heading(field: LikelihoodField, hypotheses: np.ndarray, weights: np.ndarray,
                    scan_points: np.ndarray, max_range: float, robot_radius: float,
                    clearance: float) -> float | None:
    """The heading (robot frame, rad) in which the hypotheses' predicted scans differ most,
    among those where the robot's scan (``scan_points``, m x 2, robot frame) shows a corridor
    as wide as the robot plus ``clearance`` a side, free for EXPLORE_STEP; None with fewer
    than two hypotheses, when they agree everywhere (MIN_DISAGREEMENT), or when no such
    corridor is free."""
    if hypotheses.shape[0] < 2:
        return None
    headings = np.linspace(-np.pi, np.pi, EXPLORE_HEADINGS, endpoint=False)
    open_way = corridor_lengths(scan_points, headings, robot_radius + clearance,
                                max_range) >= EXPLORE_STEP + robot_radius
    if not open_way.any():
        return None
    score = disagreement(field, hypotheses, weights / weights.sum(), headings, max_range,
                         robot_radius)
    score = np.where(open_way, score, -1.0)
    best = int(np.argmax(score))
    return float(headings[best]) if score[best] >= MIN_DISAGREEMENT else None


class Explorer:
    """A lost filter's choice of where to drive, held until it has been tried: a heading is
    kept (in the odometry frame) until the robot has driven EXPLORE_STEP from where it was
    chosen, its corridor is no longer free, or EXPLORE_PATIENCE has passed; with none, a new
    one is sought every EXPLORE_RETRY. (Chosen afresh every second, the heading swung as the
    hypotheses' weights shifted, and the robot turned to and fro on the spot, learning
    nothing: instrumented in the warehouse, docs/localization-journal.md.)"""

    def __init__(self, robot_radius: float, clearance: float) -> None:
        self.robot_radius = robot_radius  # [m]
        self.clearance = clearance  # [m] a side of the robot, in the corridor it must see free
        self._heading: float | None = None  # [rad] in the odometry frame
        self._from = np.zeros(3)  # odometry pose where it was chosen
        self._since = -np.inf  # [s] when it was last chosen (or sought)

    def heading(self, odometry: np.ndarray) -> float | None:
        """[rad, robot frame] where to drive now, or None."""
        return None if self._heading is None else float(wrap(self._heading - odometry[2]))

    def forget(self) -> None:
        """No heading (the filter is localized)."""
        self._heading = None

    def update(self, field: LikelihoodField, hypotheses: np.ndarray, weights: np.ndarray,
               scan_points: np.ndarray, max_range: float, odometry: np.ndarray, time: float) -> None:
        """After a filter update while not localized: keep the heading, or choose anew
        (:func:`explore_heading`) from the hypotheses (k, 3) and their ``weights``, the scan's
        end points (m, 2, robot frame) and the odometry pose and time of the scan."""
        if self._heading is not None:
            moved = float(np.hypot(*(np.asarray(odometry[:2]) - self._from[:2])))
            ahead = corridor_lengths(scan_points, np.array([self.heading(odometry)]),
                                     self.robot_radius + self.clearance, max_range)[0]
            if (moved < EXPLORE_STEP and time < self._since + EXPLORE_PATIENCE
                    and ahead >= EXPLORE_STEP - moved + self.robot_radius):
                return
        elif time < self._since + EXPLORE_RETRY:
            return
        self._since = time
        self._from = np.array(odometry, dtype=float)
        found = explore_heading(field, hypotheses, weights, scan_points, max_range,
                                self.robot_radius, self.clearance)
        self._heading = None if found is None else float(wrap(odometry[2] + found))
