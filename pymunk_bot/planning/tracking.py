"""Telling moving things (other robots) from static ones in successive LiDAR scans.

Reactive avoidance that treats everything as static lets two robots closing at 2 m/s each use
the whole gap to brake; predicting where a moving cluster of returns will be fixes that.
"""
from __future__ import annotations

import math

import numba
import numpy as np

CLUSTER_GAP = 0.2  # [m] neighbouring scan points farther apart start a new cluster
CLUSTER_SIZE = 0.5  # [m] clusters reaching farther than this from their centre are not tracked
BASELINE = 0.3  # [s] motion is measured against the scan this long ago
MOVED_DISTANCE = 0.08  # [m] a cluster whose returns are mostly farther from the old ones moved
MOVING_SPEED = 0.2  # [m/s] slower clusters count as standing still
TRACK_SPEED = 2.0  # [m/s] faster apparent motion is a mismatch, ignored
TRACK_RANGE = 3.5  # [m] farther clusters are not tracked
CONFIRM_DISTANCE = 0.15  # [m] a moving cluster counts once the last scan predicted it this well
ONCOMING_TIME = 4.0  # [s] something coming at us that would meet us within this...
PASS_MARGIN = 0.1  # [m] ...and pass closer than radii + safety + this is oncoming


def distance_to_polyline(points: np.ndarray, scan: np.ndarray, gap: float) -> np.ndarray:
    """Distance [m] from each of ``points`` to a scan's returns joined, in scan order, where
    neighbours are at most ``gap`` apart (the surface that scan saw)."""
    return _distance_to_polyline(np.ascontiguousarray(points, dtype=float).reshape(-1, 2),
                                 np.ascontiguousarray(scan, dtype=float).reshape(-1, 2),
                                 float(gap))


@numba.njit(cache=True, nogil=True)
def _distance_to_polyline(points: np.ndarray, scan: np.ndarray,
                          gap: float) -> np.ndarray:  # pragma: no cover - compiled
    near2 = np.full(len(points), np.inf)  # [m^2] squared distances: one root at the end
    for k in range(len(scan)):
        ax, ay = scan[k, 0], scan[k, 1]
        ex, ey = 0.0, 0.0  # the segment to the next return if they are joined, else the return
        if k + 1 < len(scan):
            ex, ey = scan[k + 1, 0] - ax, scan[k + 1, 1] - ay
            if ex * ex + ey * ey > gap * gap:
                ex, ey = 0.0, 0.0
        length2 = max(ex * ex + ey * ey, 1e-12)
        for i in range(len(points)):
            rx, ry = points[i, 0] - ax, points[i, 1] - ay
            u = min(max((rx * ex + ry * ey) / length2, 0.0), 1.0)
            dx, dy = rx - u * ex, ry - u * ey
            near2[i] = min(near2[i], dx * dx + dy * dy)
    return np.sqrt(near2)


def small_clusters(points: np.ndarray, world: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """The scan's clusters that may be something moving: (each one's indices into ``points``,
    their centres in ``world``, (k, 2)). ``points`` (robot frame) are cut where neighbouring
    returns are more than CLUSTER_GAP apart (the last joins the first across the scan's ends);
    a cluster of at least 3 returns none farther than CLUSTER_SIZE from its centre is kept."""
    if not len(points):
        return [], np.zeros((0, 2))
    jumps = np.hypot(*np.diff(points, axis=0).T) > CLUSTER_GAP
    labels = np.concatenate([[0], np.cumsum(jumps)])
    if labels[-1] > 0 and np.hypot(*(points[0] - points[-1])) <= CLUSTER_GAP:
        labels[labels == labels[-1]] = 0  # the scan wraps around
    order = np.argsort(labels, kind="stable")  # each cluster's returns together, in scan order
    cuts = np.flatnonzero(np.diff(labels[order])) + 1
    starts = np.concatenate([[0], cuts])
    counts = np.diff(np.append(starts, len(order)))
    centre = np.add.reduceat(points[order], starts, axis=0) / counts[:, None]
    spread = np.hypot(*(points[order] - np.repeat(centre, counts, axis=0)).T)
    keep = (counts >= 3) & (np.maximum.reduceat(spread, starts) <= CLUSTER_SIZE)
    centres = np.add.reduceat(world[order], starts, axis=0) / counts[:, None]
    return ([index for index, kept in zip(np.split(order, cuts), keep) if kept],
            centres[keep].reshape(-1, 2))


def median(values: np.ndarray) -> float:
    """The median of a few values (np.median's, without its overhead)."""
    ordered = np.sort(values)
    half = len(ordered) // 2
    return float(ordered[half] if len(ordered) % 2 else 0.5 * (ordered[half - 1] + ordered[half]))


class MovingObstacleTracker:
    """Remembers recent scans (world frame) and finds the clusters of returns that move."""

    def __init__(self) -> None:
        self._history: list = []  # (time [s], scan points, cluster centres), world frame
        self._moving: list = []  # (time [s], centre, velocity) of clusters that moved, world

    def update(self, stamp: float, pose, points: np.ndarray, speed: float,
               clearance: float) -> tuple[np.ndarray, tuple | None]:
        """Velocities of the scan points (robot frame, [m/s]; zero for what stands still) and
        the nearest thing coming at us that would pass too close: (ahead, aside, gap) [m] in the
        robot frame, gap being the distance between centres we want when passing it.

        ``stamp`` is when the scan was taken [s], ``pose`` our pose estimate, ``points`` the scan's
        returns in the robot frame, ``speed`` our forward speed [m/s] and ``clearance`` [m] our
        radius plus the safety margin we keep.

        The scan is cut into clusters where neighbouring returns are more than CLUSTER_GAP
        apart. A small cluster (another robot, a box) has moved when most of its points lie
        farther than MOVED_DISTANCE from the surface the scan BASELINE seconds older saw (its
        returns joined; world frame, by our pose estimate): a static surface seen from a new
        place still lies on its old returns. Its velocity is then the displacement of its centre
        from the nearest cluster centre of that scan, and it counts once the previous scan saw it
        moving the same way. Walls and other large clusters are taken as static.
        """
        velocities = np.zeros_like(points)
        x, y, theta = (float(v) for v in pose[:3])
        c, s_ = math.cos(theta), math.sin(theta)
        rotate = np.array([[c, -s_], [s_, c]])  # robot frame -> world
        world = points @ rotate.T + (x, y)
        members, centres = small_clusters(points, world)
        self._history = [h for h in self._history if h[0] < stamp and stamp - h[0] <= 2 * BASELINE]
        old = [h for h in self._history if stamp - h[0] >= BASELINE - 1e-6]
        self._history.append((stamp, world, centres))
        if not old or not len(centres) or not len(old[-1][2]):
            self._moving = []
            return velocities, None
        then, old_world, old_centres = old[-1]
        dt = stamp - then
        oncoming = None
        previous, self._moving, moving = self._moving, [], []
        for index, centre in zip(members, centres):
            if np.hypot(*(centre - (x, y))) > TRACK_RANGE:
                continue
            if median(distance_to_polyline(world[index], old_world, CLUSTER_GAP)) < MOVED_DISTANCE:
                continue  # still on the old returns: static
            shift = centre - old_centres[np.argmin(np.hypot(*(old_centres - centre).T))]
            velocity = shift / dt
            if not MOVING_SPEED <= np.hypot(*velocity) <= TRACK_SPEED:
                continue
            moving.append((centre, velocity))
            if not any(np.hypot(*(centre - c0 - v0 * (stamp - t0))) <= CONFIRM_DISTANCE
                       for t0, c0, v0 in previous):
                continue  # seen moving for the first time: wait for the next scan to confirm
            local_v = rotate.T @ velocity
            velocities[index] = local_v
            ahead, aside = rotate.T @ (centre - (x, y))
            if ahead <= 0.0 or local_v[0] > -MOVING_SPEED:
                continue
            meet = ahead / (speed - local_v[0])  # [s] until it is beside us
            size = float(np.hypot(*(world[index] - centre).T).max())
            gap = clearance + size + PASS_MARGIN
            if meet < ONCOMING_TIME and abs(aside + local_v[1] * meet) < gap and (
                    oncoming is None or ahead < oncoming[0]):
                oncoming = (float(ahead), float(aside), gap)
        self._moving = [(stamp, c0, v0) for c0, v0 in moving]
        return velocities, oncoming


PASS_AHEAD = 1.0  # [m] the point we aim at to pass something is at least this far ahead
SIDE_MEMORY = 1.0  # [s] the side chosen for an encounter holds this long after it ends


class PassingSide:
    """Keep right when something comes at us head-on (shared by ``avoid`` and ``navigate``).

    Two robots that treat each other as obstacles and meet head-on each pick a side from what
    they see; exactly head-on that is a coin toss, and when the coins differ they both step the
    same way and block each other again (the sidewalk dance). So, as in traffic, we keep right:
    we aim to pass it with ``gap`` between centres on our right, unless it is already more than
    our radius to our right (then on our left, which is shorter and what the other one, seeing
    the mirror image, does too). The side holds for the encounter.
    """

    def __init__(self) -> None:
        self._side: tuple[float, float] | None = None  # (-1 right or +1 left, last time [s])

    def target(self, now: float, oncoming: tuple | None, target: np.ndarray,
               radius: float) -> np.ndarray:
        """``target`` (robot frame [m]), or a point beside what is coming at us."""
        if oncoming is None:
            if self._side is not None and now - self._side[1] > SIDE_MEMORY:
                self._side = None
            return target
        ahead, aside, gap = oncoming
        if ahead >= float(np.hypot(*target)):
            return target  # the target comes first
        side = self._side[0] if self._side is not None else (-1.0 if aside > -radius else 1.0)
        self._side = (side, now)
        # Never aim sharply sideways: the point stays at least PASS_AHEAD ahead.
        return np.array([max(ahead, PASS_AHEAD), aside + side * gap])
