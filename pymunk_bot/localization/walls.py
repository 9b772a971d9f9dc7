"""Long straight walls as landmarks of SLAM's pose graph: they hold the heading the chain drifts.

The front end aligns each new scan with the latest keyframes (slam.py), so it measures each
heading relative to them, and with a sparse, noisy LiDAR (180-270 beams at 5-6 m) a step's
heading is pinned to only ~0.2 deg: along a 10 m aisle the chain drifts by a degree or two,
10-40 cm sideways, and a there-and-back tour shares the outbound error on both legs, so its
loop closures cannot see it (docs/localization-journal.md, "SLAM: where the error enters").

A long straight wall's *direction* is the same from wherever it is seen. So:

- :func:`long_walls` extracts the straight lines at least MIN_WALL_LENGTH long from one scan
  (robot frame): local line fits (icp.Reference.surfaces) grouped by direction and offset,
  each group split where its end points leave a gap wider than MAX_WALL_GAP along it (a row
  of racks is not a wall, nor are a doorway's two sides one) and each part refitted by total
  least squares over its raw end points, with the variance of the fitted direction (inflated
  for correlated beams, as the ICP's per-point variance).
- :class:`WallLandmarks` keeps each wall as a landmark: a wall *segment* (its ends as the
  keyframe that first saw it saw them) with a direction in the world. A later keyframe's wall
  is that landmark's observation only when it lies on the segment's line and overlaps the
  segment by MIN_OVERLAP (not any parallel wall, nor the far part of a long one: the real
  warehouse map's walls that look straight bend by 0.5-0.7 deg between their parts).
- Each observation is a factor of the pose graph (posegraph.WallFactors) between the
  keyframe's heading and the landmark's direction, under Cauchy's kernel; the graph, not the
  front end, refines every landmark's direction from every keyframe that saw it. (Fixing each
  keyframe's heading in the front end from one anchor scan was tried: one scan's direction is
  good to only 0.1-1 deg, every fix from an anchor shares its error, and the fixes jittered
  the submap the next match used.)

On by default (``SlamConfig.wall_landmarks``). Measured with the robustness benchmark (every
``slam_revisit`` row; docs/localization-journal.md, "SLAM: walls as graph landmarks" and "SLAM: why
the walls pulled the depot's headings"). On the Nav2 depot map, which they were not built
on, the first walls made 9 of 10 typical tours end farther off (median ATE 1.65 -> 2.25 cm):
rows of racks fitted as one wall whose direction depended on the racks in view, and the south
wall held to one direction across a part the map draws 0.88 deg off the rest. With walls split
at gaps the depot's medians are the walls-off ones or lower and no row has fewer runs within
5 cm. A wall's direction, as a scan fits it, moves by tenths of a degree as the robot passes
along it, an error its observations share, so each weighs as 1 in WALL_VARIANCE_SCALE and the
graph takes them in only at its optimizations after loop closures.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pymunk_bot.localization.icp import POINT_CORRELATION, Reference
from pymunk_bot.localization.posegraph import WallFactors
from pymunk_bot.localization.se2 import transform_points

MIN_WALL_LENGTH = 1.5  # [m] a straight stretch this long (end points spanning it) is a wall
DIRECTION_TOLERANCE = math.radians(4.0)  # [rad] line fits this near a peak's direction join it
OFFSET_TOLERANCE = 0.05  # [m] ... and end points this near its line
HISTOGRAM_BIN = math.radians(2.0)  # [rad] of the direction histogram
MAX_WALLS = 4  # per scan (bounds the cost)
MIN_WALL_POINTS = 10  # end points on a wall, at least
# [rad] floor of an observed direction's std: a real wall is not a perfect line (the
# warehouse map's bend 0.5-0.7 deg between parts), and consecutive scans see the same stones.
MIN_DIRECTION_STD = math.radians(0.1)
MAX_WALL_STD = math.radians(1.0)  # [rad] a wall whose direction is less sure is not used
# [m] end points farther apart than this along a line are two surfaces, not one wall: the
# Nav2 depot's rows of racks (faces 1.3 m wide, 1.5-1.7 m apart, in line within a cell) fitted
# as one wall had a direction that depended on which racks were in view, and the south wall
# is cut where a pillar stands out of it, between its parts 0.88 deg apart
# (docs/localization-journal.md, "SLAM: why the walls pulled the depot's headings").
MAX_WALL_GAP = 0.5
SAME_WALL_DISTANCE = 0.3  # [m] a wall is a landmark's when both its ends lie this near its line
MIN_OVERLAP = 0.5  # [m] ... its extent overlaps the landmark's segment by this much
SAME_WALL_GATE = math.radians(5.0)  # [rad] ... and its direction is within this of the landmark's
WALL_KERNEL = 2.0  # [std] Cauchy scale of the wall factors: an observation this far off weighs half
# The direction's variance as the graph takes it: the total-least-squares variance counts
# the beams' noise only, and that is honest about one scan (warehouse typical: true errors
# 0.10 / 0.13 / 0.20 / 0.54 deg RMS for stated 0-0.1 / 0.1-0.2 / 0.2-0.4 / 0.4-1 deg), but a real
# wall's faces are not one straight line, so the direction a scan fits moves by tenths of a
# degree as the robot passes along it, the same for all its observations from there
# (warehouse, typical, seed 5: one wall's direction from 12 keyframes along 3 m went
# -0.8 -> +0.1 deg, each stated to 0.5-0.6 deg; taken at their stated variance the walls
# twisted the graph by 0.9 deg). Each observation weighs as 1 in WALL_VARIANCE_SCALE (20
# and 40 measured on every slam_revisit row: 40 better or equal on all, 20 made the warehouse
# with uncalibrated odometry worse; docs/localization-journal.md).
WALL_VARIANCE_SCALE = 40.0


@dataclass(frozen=True)
class Wall:
    """A straight wall seen in one scan: its direction in the robot frame, modulo pi."""

    direction: float  # [rad] in [0, pi)
    variance: float  # [rad^2] of the direction
    length: float  # [m] extent of its end points along it
    ends: np.ndarray  # [m] (2, 2): its two ends, robot frame


def half_turn(angle):
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
        near = free & (np.abs(half_turn(angle - peak)) <= DIRECTION_TOLERANCE)
        free &= ~near
        if np.count_nonzero(near) < MIN_WALL_POINTS:
            continue
        # the group's mean direction (doubled angles: a direction and its opposite are one)
        doubled = 2.0 * angle[near]
        mean = 0.5 * math.atan2(float(np.sin(doubled).sum()), float(np.cos(doubled).sum()))
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
    return ((np.abs(across) <= OFFSET_TOLERANCE) & (t >= -OFFSET_TOLERANCE)
            & (t <= wall.length + OFFSET_TOLERANCE))


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
        for run in _runs(points[on], along):
            wall = _fitted(run)
            if wall is not None:
                found.append(wall)
    return found


def _runs(points: np.ndarray, along: np.ndarray) -> list[np.ndarray]:
    """``points`` on one line split where none lies within MAX_WALL_GAP of the next along it
    (``along``: the line's direction): surfaces apart, not one wall."""
    order = np.argsort(points @ along)
    splits = np.flatnonzero(np.diff(points[order] @ along) > MAX_WALL_GAP) + 1
    return [points[part] for part in np.split(order, splits)]


def _fitted(wall: np.ndarray) -> Wall | None:
    """The wall through end points ``wall`` (m, 2) by total least squares, if they are enough
    and span a wall's length."""
    if wall.shape[0] < MIN_WALL_POINTS:
        return None
    centred = wall - wall.mean(axis=0)
    values, vectors = np.linalg.eigh(centred.T @ centred / wall.shape[0])
    spread_across, spread_along = float(values[0]), float(values[1])
    if spread_along < (MIN_WALL_LENGTH / 4.0) ** 2:  # a few points, not a wall's length
        return None
    t = centred @ vectors[:, 1]
    if t.max() - t.min() < MIN_WALL_LENGTH:  # a run cut off by a gap
        return None
    # total least squares: var(direction) = var(across) / sum of squared spreads along
    variance = POINT_CORRELATION * spread_across / (wall.shape[0] * spread_along)
    direction = float(np.mod(math.atan2(vectors[1, 1], vectors[0, 1]), np.pi))
    ends = wall.mean(axis=0) + np.outer([t.min(), t.max()], vectors[:, 1])
    return Wall(direction, max(variance, MIN_DIRECTION_STD ** 2), float(t.max() - t.min()), ends)


class WallLandmarks:
    """The walls SLAM has seen, as landmarks, and every keyframe's observations of them
    (module docstring)."""

    def __init__(self) -> None:
        self._seed = np.zeros(0, dtype=np.intp)  # the keyframe that first saw each landmark
        self._ends = np.zeros((0, 2, 2))  # [m] its segment's two ends, in that keyframe's frame
        self._keyframes: list[set[int]] = []  # the keyframes that saw each landmark
        self._node: list[int] = []  # per observation: the keyframe
        self._landmark: list[int] = []  # ... the landmark
        self._direction: list[float] = []  # [rad] ... the wall's direction, keyframe frame
        self._variance: list[float] = []  # [rad^2] ... of that direction

    def __len__(self) -> int:
        return int(self._seed.size)

    @property
    def observations(self) -> int:
        """How many times keyframes have seen a landmark."""
        return len(self._node)

    def seen_again(self) -> int:
        """Landmarks seen from more than one keyframe (only they tie headings together)."""
        return sum(1 for seen in self._keyframes if len(seen) > 1)

    def observe(self, keyframe: int, keyframes: list[np.ndarray], walls: list[Wall]) -> None:
        """Walls seen by keyframe ``keyframe`` (``keyframes``: every keyframe's pose [x, y,
        theta]): each is an observation of the landmark whose segment it overlaps most (its
        line and direction near), or seeds a new landmark."""
        pose = np.asarray(keyframes[keyframe], dtype=float)
        taken: set[int] = set()
        for wall in walls:
            if wall.variance > MAX_WALL_STD ** 2:
                continue
            landmark = self._match(keyframes, pose, wall, taken)
            if landmark is None:
                landmark = len(self)
                self._seed = np.append(self._seed, keyframe)
                self._ends = np.concatenate([self._ends, wall.ends[None]])
                self._keyframes.append(set())
            taken.add(landmark)
            self._keyframes[landmark].add(keyframe)
            self._node.append(keyframe)
            self._landmark.append(landmark)
            self._direction.append(wall.direction)
            self._variance.append(wall.variance)

    def _match(self, keyframes: list[np.ndarray], pose: np.ndarray, wall: Wall,
               taken: set[int]) -> int | None:
        """The landmark ``wall`` seen from ``pose`` is (None: a new one)."""
        if not len(self):
            return None
        seed = np.asarray(keyframes, dtype=float)[self._seed]  # (n, 3)
        c, s = np.cos(seed[:, 2]), np.sin(seed[:, 2])
        ex, ey = self._ends[:, :, 0], self._ends[:, :, 1]
        ends = np.stack([seed[:, 0, None] + c[:, None] * ex - s[:, None] * ey,
                         seed[:, 1, None] + s[:, None] * ex + c[:, None] * ey], axis=-1)  # (n, 2, 2)
        along = ends[:, 1] - ends[:, 0]
        along /= np.maximum(np.linalg.norm(along, axis=1), 1e-12)[:, None]
        across = np.column_stack([-along[:, 1], along[:, 0]])
        new = transform_points(pose, wall.ends)  # (2, 2) world
        distance = np.abs(new @ across.T - np.einsum("nd,nd->n", across, ends[:, 0])).max(axis=0)
        theirs = np.sort(np.einsum("nkd,nd->nk", ends, along), axis=1)
        mine = np.sort(new @ along.T, axis=0)  # (2, n)
        overlap = np.minimum(mine[1], theirs[:, 1]) - np.maximum(mine[0], theirs[:, 0])
        miss = half_turn(float(pose[2]) + wall.direction - np.arctan2(along[:, 1], along[:, 0]))
        same = ((distance <= SAME_WALL_DISTANCE) & (overlap >= MIN_OVERLAP)
                & (np.abs(miss) <= SAME_WALL_GATE))
        if taken:
            same[list(taken)] = False
        if not same.any():
            return None
        return int(np.flatnonzero(same)[np.argmax(overlap[same])])

    def factors(self, keyframes: list[np.ndarray] | np.ndarray) -> WallFactors | None:
        """The graph's factors of the landmarks seen from more than one keyframe, each
        landmark's direction started at the weighted mean of its observations at these
        keyframe poses; None when there are none."""
        if not self._node:
            return None
        node = np.asarray(self._node, dtype=np.intp)
        landmark = np.asarray(self._landmark, dtype=np.intp)
        shared = np.array([len(seen) > 1 for seen in self._keyframes])
        keep = shared[landmark]
        if not keep.any():
            return None
        renumber = np.cumsum(shared) - 1
        node, landmark = node[keep], renumber[landmark[keep]]
        direction = np.asarray(self._direction)[keep]
        information = 1.0 / (WALL_VARIANCE_SCALE * np.asarray(self._variance)[keep])
        world = np.asarray(keyframes, dtype=float)[node, 2] + direction
        count = int(np.count_nonzero(shared))
        # doubled angles: a direction and its opposite are one
        mean = 0.5 * np.arctan2(np.bincount(landmark, information * np.sin(2 * world), count),
                                np.bincount(landmark, information * np.cos(2 * world), count))
        return WallFactors(node, landmark, direction, information, mean, WALL_KERNEL)
