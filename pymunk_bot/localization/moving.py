"""Returns from things that move, found without a map pose: scans compared through odometry.

dynamic.py finds returns *short of the map*, which needs a pose on the map: from a wrong pose
(a global start, a kidnapping) it would hide the very beams that contradict it. This test needs
none. Each fresh scan is kept, with the odometry pose it was taken at, for ``window`` seconds.
A new return is *moving* when, seen from where an earlier scan was taken (the odometry between
them moves it into that scan's frame), it lies in space that scan's beam in its direction saw
free: that beam reached more than ``margin`` beyond it (a free-space violation: something entered
space seen empty a moment ago). A walker crossing or approaching the beam is caught; so is the
rest of its outline: a short run of neighbouring returns (a person-sized blob, at most ``blob``
across) holding a moving return is moving as a whole.

Not caught by that: a person standing still the whole window (nothing entered free space) and
one walking straight away along the beam (the space it enters was behind it, unseen). With a
``track`` radius (MCL's ``moving_track``), returns near one found moving in the last ``window``
are moving too, which keeps a walker seen moving flagged when it stops or walks away. A return
that was hidden before (behind something nearer) is never flagged: the earlier beam stopped
short of it. Of an earlier scan's beams, the two bracketing the direction and one more on each
side are asked, and the shortest counts: a wall seen edge-on or a small odometry error between
the scans does not make a static return look moving.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np
from scipy.spatial import cKDTree

from pymunk_bot.localization.se2 import between, scan_points, transform_points

MAX_KEPT_SCANS = 16  # earlier scans compared with (bounds the memory and the cost per scan)
NEIGHBOURS = 2  # beams either side of the nearest one whose shortest range counts
# Neighbouring returns farther apart than this belong to different things (a blob's outline
# is one run of returns with steps below it) [m].
BLOB_GAP = 0.15


class _Kept:
    """One earlier scan: its ranges, beam grid and the odometry pose it was taken at."""

    __slots__ = ("ranges", "first_angle", "step", "full_circle", "mount", "odometry", "time")

    def __init__(self, scan, odometry: np.ndarray) -> None:
        ranges = np.asarray(scan.ranges, dtype=float).copy()
        usable = np.isfinite(ranges) & (ranges >= scan.min_range)
        # A beam with no return saw free space up to max_range; an unusable one saw nothing.
        self.ranges = np.where(usable, np.minimum(ranges, scan.max_range), 0.0)
        angles = np.asarray(scan.angles, dtype=float)
        self.first_angle = float(angles[0])
        n = angles.size
        self.step = float(angles[-1] - angles[0]) / (n - 1) if n > 1 else 2.0 * math.pi
        self.full_circle = self.step * n >= 2.0 * math.pi - 1e-6
        self.mount = np.array([scan.offset[0], scan.offset[1]], dtype=float)
        self.odometry = np.asarray(odometry, dtype=float).copy()
        self.time = float(scan.time)

    def reach(self, bearing: np.ndarray) -> np.ndarray:
        """How far this scan saw free space along each ``bearing`` [rad, its robot frame]: the
        shortest range of the beams around it; 0 outside its field of view."""
        n = self.ranges.size
        rel = np.mod(bearing - self.first_angle, 2.0 * math.pi) / self.step
        nearest = np.rint(rel).astype(np.int64)
        if self.full_circle:
            nearest %= n
            inside = np.ones(nearest.shape, dtype=bool)
        else:  # within half a step of the field of view; just below the first beam wraps
            below = rel >= 2.0 * math.pi / self.step - 0.5
            inside = below | (rel <= n - 0.5)
            nearest = np.where(below | ~inside, 0, nearest)
        offsets = np.arange(-NEIGHBOURS, NEIGHBOURS + 1)
        index = nearest[:, None] + offsets[None, :]
        index = index % n if self.full_circle else np.clip(index, 0, n - 1)
        return np.where(inside, self.ranges[index].min(axis=1), 0.0)


class MovingReturns:
    """Keeps the recent scans and flags the returns of a new one that entered space they saw free.

    ``window`` [s]: how far back scans are compared (a walker at 1 m/s moves 0.5 m in 0.5 s);
    ``margin`` [m]: how far beyond a return an earlier beam must have reached; ``blob`` [m]: the
    largest outline flagged whole when one of its returns is moving (0: returns one by one).
    ``scans``: how many are kept at most, ``spacing`` [s]: the least time between two kept
    (default: ``window`` / ``scans``, so that they span the window). ``track`` [m]: a return
    within this of one that :meth:`flag` found moving in the last ``window`` (odometry frame)
    is moving too (0: no memory); see :meth:`flag`.
    """

    def __init__(self, window: float, margin: float, blob: float, scans: int = MAX_KEPT_SCANS,
                 spacing: float | None = None, track: float = 0.0) -> None:
        self.window = window
        self.margin = margin
        self.blob = blob
        self.track = track
        self.spacing = window / scans if spacing is None else spacing
        self._kept: deque[_Kept] = deque(maxlen=scans)
        # (time [s], odometry-frame points (k, 2)) of the returns flag() found moving
        self._seen_moving: deque[tuple[float, np.ndarray]] = deque(maxlen=scans)

    def observe(self, scan, odometry: np.ndarray) -> None:
        """Keep ``scan`` (taken at ``odometry`` [x, y, theta]) for the scans that follow, at
        least ``spacing`` after the last one kept."""
        if self._kept and scan.time - self._kept[-1].time < self.spacing:
            return
        self._kept.append(_Kept(scan, odometry))
        while self._kept and scan.time - self._kept[0].time > self.window:
            self._kept.popleft()

    def forget(self) -> None:
        """Drop every kept scan (their poses no longer hold, e.g. after a SLAM graph moved)."""
        self._kept.clear()

    def flag(self, scan, odometry: np.ndarray) -> np.ndarray:
        """Boolean per return of ``scan`` (in ``scan_points`` order, max-range beams left out),
        taken at ``odometry``: which are moving. Compared with the kept scans older than it.

        With ``track``: also the returns within ``track`` of a return an earlier call found
        entering free space in the last ``window`` (both through the odometry): a walker seen
        moving a moment ago that now stands, or walks straight away along the beam, enters no
        space seen free. Only returns seen entering free space are remembered, not those
        flagged by the memory itself, so a static return flagged by mistake (an odometry error)
        is forgotten after ``window``."""
        points, index = scan_points(scan)
        moving = np.zeros(points.shape[0], dtype=bool)
        if points.shape[0] == 0:
            return moving
        odometry = np.asarray(odometry, dtype=float)
        for kept in self._kept:
            if kept.time >= scan.time or scan.time - kept.time > self.window:
                continue
            then = transform_points(between(kept.odometry, odometry), points) - kept.mount
            distance = np.hypot(then[:, 0], then[:, 1])
            moving |= kept.reach(np.arctan2(then[:, 1], then[:, 0])) > distance + self.margin
        if self.blob > 0 and moving.any():
            moving = _whole_blobs(points, index, moving, self.blob)
        if self.track > 0:
            moving = self._tracked(points, index, moving, odometry, float(scan.time))
        return moving

    def _tracked(self, points: np.ndarray, index: np.ndarray, moving: np.ndarray,
                 odometry: np.ndarray, time: float) -> np.ndarray:
        """``moving`` (found entering free space) widened to the returns within ``track`` of
        one remembered from the last ``window``; remembers ``moving``'s."""
        while self._seen_moving and time - self._seen_moving[0][0] > self.window:
            self._seen_moving.popleft()
        world = transform_points(odometry, points)
        out = moving.copy()
        if self._seen_moving:
            earlier = np.concatenate([p for _, p in self._seen_moving])
            if earlier.shape[0]:
                near = cKDTree(earlier).query(world, distance_upper_bound=self.track)[0]
                out |= np.isfinite(near)
                if self.blob > 0:
                    out = _whole_blobs(points, index, out, self.blob)
        if moving.any():
            self._seen_moving.append((time, world[moving]))
        return out


def _whole_blobs(points: np.ndarray, index: np.ndarray, moving: np.ndarray, blob: float) -> np.ndarray:
    """``moving`` widened to every run of neighbouring returns (consecutive beams, steps below
    BLOB_GAP) at most ``blob`` across that holds a moving return."""
    step = np.hypot(*np.diff(points, axis=0).T)
    breaks = (np.diff(index) != 1) | (step > BLOB_GAP)
    run = np.concatenate([[0], np.cumsum(breaks)])  # run label per return
    count = run[-1] + 1
    first = np.searchsorted(run, np.arange(count), side="left")
    last = np.searchsorted(run, np.arange(count), side="right") - 1
    width = np.hypot(*(points[last] - points[first]).T)
    hit = np.bincount(run, weights=moving.astype(float), minlength=count) > 0
    return moving | (hit & (width <= blob))[run]
