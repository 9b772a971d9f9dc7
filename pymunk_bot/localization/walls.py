"""Heading anchored to long walls: SLAM's front end holds its heading where its matches cannot.

The front end aligns each new scan with the latest keyframes (slam.py), so it measures the
heading relative to them and a small error per step adds up: instrumented on the warehouse
with uncalibrated odometry (seeds 2 and 5, 5-6 m LiDAR), a few steps whose match pinned the
heading loosely (0.3-0.6 deg std) left the estimate 0.5-2 deg off for good, and along a 10 m
aisle that is 10-40 cm sideways. A long straight wall's *direction* fixes the heading from
anywhere it is seen, however far along the wall the robot is. So:

- :func:`long_walls` extracts the straight lines at least MIN_WALL_LENGTH long from one scan
  (robot frame): local line fits (icp.Reference.surfaces) grouped by direction and offset,
  each group refitted by total least squares over its raw end points, with the variance of
  the fitted direction (inflated for correlated beams, as the ICP's per-point variance).
- :class:`WallAnchors` remembers, for each wall direction of the world (modulo pi: parallel
  walls are the same direction), the keyframe that first saw it and the direction it saw.
  A later keyframe that sees a wall within a gate of an anchor's direction measures its own
  heading relative to that older keyframe: theta_new - theta_old = phi_old - phi_new (mod pi).
  The front end fuses it with the match (a Kalman update of the match's Gaussian) and the
  pose graph gets it as a heading-only edge under Cauchy's kernel, so a wall mistaken for
  another cannot bend the map.

Off by default (``wall_heading``): measured with the robustness benchmark it did not help.
A single scan's wall direction at 5-6 m is good to 0.1-1 deg, no better than the chained
matches over many keyframes, every fix from one anchor shares that anchor's error, and the
walls of the real warehouse map that look straight bend by 0.5-0.7 deg between their parts
(docs/localization.md, "SLAM: the heading").
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pymunk_bot.localization.icp import POINT_CORRELATION, Reference
from pymunk_bot.localization.se2 import transform_points

MIN_WALL_LENGTH = 1.5  # [m] a straight stretch this long (end points spanning it) is a wall
DIRECTION_TOLERANCE = math.radians(4.0)  # [rad] line fits this near a peak's direction join it
OFFSET_TOLERANCE = 0.05  # [m] ... and end points this near its line
HISTOGRAM_BIN = math.radians(2.0)  # [rad] of the direction histogram
MAX_WALLS = 4  # per scan (bounds the cost)
MIN_WALL_POINTS = 10  # end points on a wall, at least
MIN_DIRECTION_STD = math.radians(0.05)  # [rad] floor of a wall direction's std
ANCHOR_SEPARATION = math.radians(10.0)  # [rad] a wall this far in direction from an anchor is another
SAME_WALL_DISTANCE = 0.3  # [m] a wall is an anchor's when both its ends lie this near its line
SAME_WALL_GAP = 1.0  # [m] ... and its extent overlaps the anchor's or falls short by at most this
ANCHOR_GATE_STD = 3.0  # [std] a wall matches an anchor within this many standard deviations
MAX_ANCHOR_GATE = math.radians(5.0)  # [rad] ... and never farther (half ANCHOR_SEPARATION)
MAX_ANCHOR_STD = math.radians(1.0)  # [rad] a wall's direction this sure, at most, anchors
MAX_ANCHORS = 2000  # bounds the cost of matching (vectorised over anchors)


@dataclass(frozen=True)
class Wall:
    """A straight wall seen in one scan: its direction in the robot frame, modulo pi."""

    direction: float  # [rad] in [0, pi)
    variance: float  # [rad^2] of the direction
    length: float  # [m] extent of its end points along it
    ends: np.ndarray  # [m] (2, 2): its two ends, robot frame


@dataclass(frozen=True)
class HeadingFix:
    """A keyframe's heading measured against an older keyframe's wall."""

    anchor: int  # the older keyframe
    heading: float  # [rad] the new keyframe's heading it implies (world frame)
    relative: float  # [rad] new heading minus the anchor keyframe's
    variance: float  # [rad^2] of ``relative`` (the two walls' directions)
    world_variance: float  # [rad^2] of ``heading`` (the anchor keyframe's own added)
    shared_variance: float  # [rad^2] the part every fix from this anchor shares (its own)


def _half_turn(angle):
    """Angles wrapped to [-pi/2, pi/2) [rad]: directions modulo pi."""
    return (np.asarray(angle) + 0.5 * np.pi) % np.pi - 0.5 * np.pi


def long_walls(points: np.ndarray) -> list[Wall]:
    """The straight walls at least MIN_WALL_LENGTH long among a scan's end points (m, 2),
    robot frame, longest first (at most MAX_WALLS)."""
    fits = Reference.surfaces(points)
    if fits.points.shape[0] < MIN_WALL_POINTS:
        return []
    angle = np.mod(np.arctan2(fits.normals[:, 1], fits.normals[:, 0]) + 0.5 * np.pi, np.pi)
    free = np.ones(angle.size, dtype=bool)
    walls: list[Wall] = []
    bins = int(round(np.pi / HISTOGRAM_BIN))
    for _ in range(MAX_WALLS):
        if np.count_nonzero(free) < MIN_WALL_POINTS:
            break
        counts = np.bincount((angle[free] / HISTOGRAM_BIN).astype(np.intp) % bins, minlength=bins)
        peak = (np.argmax(counts) + 0.5) * HISTOGRAM_BIN
        near = free & (np.abs(_half_turn(angle - peak)) <= DIRECTION_TOLERANCE)
        free &= ~near
        if np.count_nonzero(near) < MIN_WALL_POINTS:
            continue
        # the group's mean direction (doubled angles: a direction and its opposite are one)
        mean = 0.5 * math.atan2(float(np.sin(2 * angle[near]).sum()), float(np.cos(2 * angle[near]).sum()))
        along = np.array([math.cos(mean), math.sin(mean)])
        across = np.array([-along[1], along[0]])
        for wall in _walls_along(points, fits.points[near], along, across):
            walls.append(wall)
            free &= ~_on_wall(fits.points, wall)  # its noisier fits are not another wall
    walls.sort(key=lambda w: -w.length)
    return walls[:MAX_WALLS]


def _on_wall(points: np.ndarray, wall: Wall) -> np.ndarray:
    """Which of ``points`` (m, 2) lie on ``wall`` (within OFFSET_TOLERANCE of its segment)."""
    start, end = wall.ends
    along = (end - start) / max(float(np.hypot(*(end - start))), 1e-12)
    t = (points - start) @ along
    across = (points - start) @ np.array([-along[1], along[0]])
    return (np.abs(across) <= OFFSET_TOLERANCE) & (t >= -OFFSET_TOLERANCE) & (t <= wall.length + OFFSET_TOLERANCE)


def _walls_along(points: np.ndarray, centres: np.ndarray, along: np.ndarray,
                 across: np.ndarray) -> list[Wall]:
    """The walls among line fits ``centres`` of one direction: split by offset across it,
    each long enough refitted over the raw ``points`` on its line."""
    offset = centres @ across
    order = np.argsort(offset)
    splits = np.flatnonzero(np.diff(offset[order]) > OFFSET_TOLERANCE) + 1
    found = []
    for group in np.split(order, splits):
        s = centres[group] @ along
        if s.max() - s.min() < MIN_WALL_LENGTH:
            continue
        line = float(np.median(offset[group]))
        t = points @ along
        on = (np.abs(points @ across - line) <= OFFSET_TOLERANCE) & (t >= s.min()) & (t <= s.max())
        if np.count_nonzero(on) < MIN_WALL_POINTS:
            continue
        wall = points[on]
        centred = wall - wall.mean(axis=0)
        values, vectors = np.linalg.eigh(centred.T @ centred / wall.shape[0])
        spread_across, spread_along = float(values[0]), float(values[1])
        if spread_along < (MIN_WALL_LENGTH / 4.0) ** 2:  # a few points, not a wall's length
            continue
        # total least squares: var(direction) = var(across) / sum of squared spreads along
        variance = POINT_CORRELATION * spread_across / (wall.shape[0] * spread_along)
        direction = float(np.mod(math.atan2(vectors[1, 1], vectors[0, 1]), np.pi))
        t = (wall - wall.mean(axis=0)) @ vectors[:, 1]
        ends = wall.mean(axis=0) + np.outer([t.min(), t.max()], vectors[:, 1])
        found.append(Wall(direction, max(variance, MIN_DIRECTION_STD ** 2),
                          float(t.max() - t.min()), ends))
    return found


class WallAnchors:
    """The world's long walls, each tied to the keyframe that first saw it (module docstring).
    A wall is matched by identity (its line within SAME_WALL_DISTANCE, its extent within
    SAME_WALL_GAP), not merely by direction: walls of a real map that look parallel are
    not quite (the warehouse's: a persistent 0.4-0.5 deg heading error when any parallel
    wall could anchor)."""

    def __init__(self) -> None:
        self._keyframe = np.zeros(0, dtype=np.intp)  # the keyframe that saw each anchor
        self._direction = np.zeros(0)  # [rad] its direction in that keyframe's frame
        self._ends = np.zeros((0, 2, 2))  # [m] its two ends in that keyframe's frame
        self._variance = np.zeros(0)  # [rad^2] of its direction
        self._heading_variance = np.zeros(0)  # [rad^2] that keyframe's heading, world frame

    def __len__(self) -> int:
        return int(self._keyframe.size)

    def _same(self, keyframes: list[np.ndarray], pose: np.ndarray, wall: Wall,
              direction_gate: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Which anchors ``wall``, seen from ``pose``, is (its line near theirs, its extent
        near theirs, its direction within ``direction_gate`` [rad]), and the direction's
        miss [rad] (the wall's world direction less each anchor's)."""
        seen_from = np.asarray(keyframes, dtype=float)[self._keyframe]  # (n, 3)
        c, s = np.cos(seen_from[:, 2]), np.sin(seen_from[:, 2])
        ex, ey = self._ends[:, :, 0], self._ends[:, :, 1]
        ends = np.stack([seen_from[:, 0, None] + c[:, None] * ex - s[:, None] * ey,
                         seen_from[:, 1, None] + s[:, None] * ex + c[:, None] * ey], axis=-1)
        world = seen_from[:, 2] + self._direction
        along = np.column_stack([np.cos(world), np.sin(world)])
        across = np.column_stack([-along[:, 1], along[:, 0]])
        new = transform_points(pose, wall.ends)  # (2, 2) world
        offset = np.einsum("nd,nd->n", across, ends[:, 0])
        distance = np.abs(new @ across.T - offset).max(axis=0)
        theirs = np.einsum("nkd,nd->nk", ends, along)
        mine = new @ along.T  # (2, n)
        gap = np.maximum(mine.min(axis=0) - theirs.max(axis=1), theirs.min(axis=1) - mine.max(axis=0))
        miss = _half_turn(float(pose[2]) + wall.direction - world)
        same = (distance <= SAME_WALL_DISTANCE) & (gap <= SAME_WALL_GAP) & (np.abs(miss) <= direction_gate)
        return same, miss

    def fix(self, keyframes: list[np.ndarray], walls: list[Wall], pose: np.ndarray,
            heading_variance: float) -> HeadingFix | None:
        """The best heading fix for a keyframe at ``pose`` [x, y, theta], its heading unsure
        by ``heading_variance`` [rad^2] relative to the world, that sees ``walls``: the
        anchor matched with the least variance, among those within the gate; None when no
        wall is an anchor's."""
        best: HeadingFix | None = None
        if not len(self):
            return None
        for wall in walls:
            variance = wall.variance + self._variance
            gate = np.minimum(ANCHOR_GATE_STD * np.sqrt(heading_variance + self._heading_variance + variance),
                              MAX_ANCHOR_GATE)
            same, miss = self._same(keyframes, pose, wall, gate)
            if not same.any():
                continue
            k = int(np.flatnonzero(same)[np.argmin(variance[same])])
            if best is not None and variance[k] >= best.variance:
                continue
            anchor = int(self._keyframe[k])
            measured = float(pose[2]) - float(miss[k])
            best = HeadingFix(anchor, measured,
                              math.remainder(measured - float(keyframes[anchor][2]), math.tau),
                              float(variance[k]), float(variance[k] + self._heading_variance[k]),
                              float(self._variance[k] + self._heading_variance[k]))
        return best

    def add(self, keyframe: int, keyframes: list[np.ndarray], walls: list[Wall],
            heading_variance: float) -> None:
        """Walls of keyframe ``keyframe`` (its heading unsure by ``heading_variance`` [rad^2])
        that no anchor is yet become anchors, if their direction is sure enough."""
        pose = np.asarray(keyframes[keyframe], dtype=float)
        for wall in walls:
            if len(self) >= MAX_ANCHORS or wall.variance > MAX_ANCHOR_STD ** 2:
                continue
            if len(self) and self._same(keyframes, pose, wall, ANCHOR_SEPARATION)[0].any():
                continue
            self._keyframe = np.append(self._keyframe, keyframe)
            self._direction = np.append(self._direction, wall.direction)
            self._ends = np.concatenate([self._ends, wall.ends[None]])
            self._variance = np.append(self._variance, wall.variance)
            self._heading_variance = np.append(self._heading_variance, heading_variance)


def fuse_heading(pose: np.ndarray, match_covariance: np.ndarray, heading_variance: float,
                 fix: HeadingFix) -> tuple[np.ndarray, float]:
    """A keyframe's pose (3,), its heading unsure by ``heading_variance`` [rad^2] relative to
    the world, updated by a wall's heading ``fix`` (Kalman, scalar); its position moves with
    the heading as the scan match's covariance (3x3) couples them. Returns the pose and its
    heading's variance after: never below the anchor's own, which every later fix from the
    same anchor shares (fixes one after another are not independent)."""
    gain = heading_variance / (heading_variance + fix.world_variance)
    turn = gain * math.remainder(fix.heading - float(pose[2]), math.tau)
    fused = np.array(pose, dtype=float)
    fused[:2] += match_covariance[:2, 2] / max(float(match_covariance[2, 2]), 1e-18) * turn
    fused[2] = math.remainder(float(fused[2]) + turn, math.tau)
    return fused, max((1.0 - gain) * heading_variance, min(fix.shared_variance, heading_variance))
