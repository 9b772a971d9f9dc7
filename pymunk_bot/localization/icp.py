"""Point-to-line ICP (Censi's PLICP idea, Gauss-Newton form): align a scan with reference lines.

The reference is a submap of local line fits (:meth:`Reference.surfaces`): centroids and
normals of the neighbourhoods of the submap's end points, each fit of one face of a surface
(the side its scans saw it from). Each scan point is paired with the nearest fit (scipy's
cKDTree) within ``max_pair`` that faces the sensor; its error is its distance to that line,
n . (R p + t - q), weighed by Cauchy's kernel and by how well its neighbourhood is a line (a
corner or a curve fitted as one is a less certain line: :meth:`Reference.surfaces`); an
optional prior (the odometry) makes the match a maximum a posteriori one. Continuous
geometry: no grid, so no quantisation bias.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from pymunk_bot.localization.scanmatch import MIN_POINTS, Match
from pymunk_bot.localization.se2 import transform_points, wrap

POINT_CORRELATION = 3.0  # variance inflation for correlated neighbouring beams (as ekf's match_cov_scale)
MIN_POINT_STD = 0.002  # [m] floor of the per-point residual std
SURFACE_RADIUS = 0.2  # [m] neighbourhood of a reference point's line fit
SURFACE_MAX_RADIUS = 0.5  # [m] the widest it grows to where points are sparse
SURFACE_NEIGHBOURS = 32  # at most this many neighbours per fit (enough to fill SURFACE_RADIUS)
SURFACE_CELL = 0.04  # [m] the submap's points are thinned to one per cell of this size
SURFACE_MIN_POINTS = 5  # fewer neighbours within SURFACE_MAX_RADIUS: no fit
SURFACE_THINNESS = 0.4  # std across / std along the line at most this
# An oriented reference: the nearest fits asked per scan point, of which the nearest that faces
# the sensor is its pair (the other face of a thin wall is the next nearest, 10 cm away)
SIDE_CANDIDATES = 3


class Reference:
    """World points with normals and weights, indexed for nearest-neighbour pairing."""

    def __init__(self, points: np.ndarray, normals: np.ndarray,
                 weights: np.ndarray | None = None, oriented: bool = False) -> None:
        self.points, self.normals = points, normals
        # normals point out of the surface, towards where it was seen from (surfaces' facing)
        self.oriented = oriented
        # how much a scan point paired with each line counts (1: a line as thin as most)
        self.weights = np.ones(points.shape[0]) if weights is None else weights
        self.tree = cKDTree(points) if points.shape[0] else None

    @classmethod
    def surfaces(cls, points: np.ndarray, radius: float = SURFACE_RADIUS,
                 weighed: bool = True, facing: np.ndarray | None = None) -> "Reference":
        """Local line fits of a cloud (the end points of several scans, world frame): for each
        point, the centroid and normal of its neighbours within ``radius`` (at least
        SURFACE_MIN_POINTS, thin enough to be a line: clutter is left out). Fitted
        over every scan of the submap, the lines average the range noise out; a normal from a
        point's two neighbours in its own scan was tilted by about 6 deg at 5 m with 180 beams
        and 2.5 cm noise, and pairing with a raw noisy point added that point's noise.

        Each fit's weight is 2 s / (s + v): v its neighbours' variance across the line, s the
        median of v over the fits (most are stretches of wall: s is the cloud's noise). A
        stretch of wall weighs about 1, one seen through many scans up to 2, a corner or a
        rack's end taken for a line (v several times s) a few tenths. Weighed alike, such fits
        turned every match a little towards the scan's turn: a scan matched to the other
        scans at their *true* poses, no range noise, warehouse, came out 0.07 deg off a
        keyframe, 0.025 deg one way on average, 5 deg over a tour (now 0.005 deg off);
        docs/localization-journal.md, "SLAM: lines that are not lines". ``weighed`` False: every fit 1.

        ``facing`` (n, 2): per point, the unit vector from it towards the sensor that saw it.
        Given, each fit is of one face: its neighbours on the other side of its line (seen
        from behind it) are left out and the line refitted, and its normal points towards the
        side it was seen from (``oriented``: icp then pairs a point only with a face towards
        the sensor). An office's 10 cm walls, seen from both rooms, had both faces in one
        neighbourhood: the line lay between them, and a scan of one face was paired with the
        other (docs/localization-journal.md, "SLAM: the two faces of a wall")."""
        oriented = facing is not None
        empty = cls(np.empty((0, 2)), np.empty((0, 2)), oriented=oriented)
        if points.shape[0] < SURFACE_MIN_POINTS:
            return empty
        points, facing = _thinned(points, facing)
        n = points.shape[0]
        if n < SURFACE_MIN_POINTS:
            return empty
        # Where a sparse scan leaves fewer than SURFACE_MIN_POINTS within ``radius`` (one scan
        # of 180 beams has 17 cm between points at 5 m), the neighbourhood widens to hold
        # them, up to SURFACE_MAX_RADIUS: else the first keyframes had no surfaces to match.
        dist, idx = cKDTree(points).query(points, k=SURFACE_NEIGHBOURS,
                                          distance_upper_bound=max(radius, SURFACE_MAX_RADIUS))
        reach = np.maximum(radius, dist[:, SURFACE_MIN_POINTS - 1])  # inf: too few within max
        member = (dist <= reach[:, None]) & (idx < n)  # (n, k) each fit's neighbours
        idx = np.where(member, idx, 0)
        near = points[idx]  # (n, k, 2)
        count, centroid, values, vectors = _line_fits(near, member)
        normals = vectors[:, :, 0]
        if facing is not None:
            side = np.einsum("ni,ni->n", facing, normals) >= 0.0  # which side each point saw
            member &= (np.einsum("nki,ni->nk", facing[idx], normals) >= 0.0) == side[:, None]
            count, centroid, values, vectors = _line_fits(near, member)
            normals = vectors[:, :, 0]
            normals = normals * np.where(np.einsum("ni,ni->n", facing, normals) >= 0.0, 1.0, -1.0)[:, None]
        keep = (count >= SURFACE_MIN_POINTS) & (values[:, 0] <= SURFACE_THINNESS ** 2 * values[:, 1])
        if not keep.any():
            return empty
        if not weighed:
            return cls(centroid[keep], normals[keep], oriented=oriented)
        across = values[keep, 0]  # [m^2]
        typical = max(float(np.median(across)), MIN_POINT_STD ** 2)
        return cls(centroid[keep], normals[keep], 2.0 * typical / (typical + across), oriented)


def seen_from(pose: np.ndarray, points: np.ndarray,
              sensor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A scan's robot-frame end ``points`` (m, 2) placed at ``pose`` [x, y, theta]: their world
    positions (m, 2) and, per point, the unit vector towards the ``sensor`` (robot frame [m],
    the LiDAR's mount) that saw it (:meth:`Reference.surfaces`' ``facing``)."""
    world = transform_points(pose, points)
    towards = transform_points(pose, np.asarray(sensor, dtype=float).reshape(1, 2)) - world
    return world, towards / np.maximum(np.hypot(towards[:, 0], towards[:, 1]), 1e-12)[:, None]


def _thinned(points: np.ndarray, facing: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
    """One point per SURFACE_CELL (the centroid of those in it), with the mean of their
    ``facing`` (renormalised): overlapping scans would otherwise pack a point's nearest
    neighbours into a few centimetres of wall."""
    _, cell, per_cell = np.unique(np.floor(points / SURFACE_CELL).astype(np.int64), axis=0,
                                  return_inverse=True, return_counts=True)
    cell = cell.ravel()
    thinned = np.column_stack([np.bincount(cell, points[:, 0]), np.bincount(cell, points[:, 1])]) / per_cell[:, None]
    if facing is None:
        return thinned, None
    mean = np.column_stack([np.bincount(cell, facing[:, 0]), np.bincount(cell, facing[:, 1])])
    return thinned, mean / np.maximum(np.hypot(mean[:, 0], mean[:, 1]), 1e-12)[:, None]


def _line_fits(near: np.ndarray,
               member: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per fit, of its neighbours ``near`` (n, k, 2) where ``member`` (n, k): their count,
    centroid (n, 2) and the eigenvalues (n, 2, ascending) and eigenvectors (n, 2, 2; column 0
    the normal) of their covariance."""
    count = np.count_nonzero(member, axis=1)
    weight = member / np.maximum(count, 1)[:, None]
    centroid = np.einsum("nk,nki->ni", weight, near)
    centred = near - centroid[:, None, :]
    cov = np.einsum("nk,nki,nkj->nij", weight, centred, centred)
    values, vectors = np.linalg.eigh(cov)
    return count, centroid, values, vectors


def _pairs(reference: Reference, world: np.ndarray, sensor: np.ndarray,
           radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Which ``world`` points (m, 2) have a pair within ``radius``, and its index: the nearest
    fit, or for an oriented reference the nearest of SIDE_CANDIDATES that faces ``sensor``
    (world frame, 2)."""
    assert reference.tree is not None
    if not reference.oriented:
        dist, idx = reference.tree.query(world, distance_upper_bound=radius)
        found = np.isfinite(dist)
        return found, np.where(found, idx, 0)
    dist, idx = reference.tree.query(world, k=SIDE_CANDIDATES, distance_upper_bound=radius)
    found = np.isfinite(dist)
    idx = np.where(found, idx, 0)
    usable = found & (np.einsum("mj,mkj->mk", world - sensor, reference.normals[idx]) < 0.0)
    first = np.argmax(usable, axis=1)
    rows = np.arange(world.shape[0])
    return usable[rows, first], idx[rows, first]


def icp(reference: Reference, points: np.ndarray, guess: np.ndarray, iterations: int = 20,
        max_pair: float = 0.3, huber: float = 0.05, cov_scale: float = 1.0,
        prior: np.ndarray | None = None, start: np.ndarray | None = None,
        sensor: np.ndarray | None = None) -> Match:
    """Align robot-frame ``points`` (m, 2) with ``reference``, from ``guess``. ``prior``: the
    information matrix (3x3, world frame) of ``guess`` as a measurement of the pose (odometry):
    the match is then the maximum a posteriori pose, which holds the directions the scan does
    not fix (a corridor's length) where the odometry puts them instead of letting them slide.
    ``start``: the pose the iterations start from, when not ``guess`` (the prior stays there).
    ``sensor``: where the points were seen from (robot frame [m]; the origin by default): an
    oriented reference pairs a point only with a face towards it."""
    origin = np.zeros((1, 2)) if sensor is None else np.asarray(sensor, dtype=float).reshape(1, 2)
    pose = np.array(guess if start is None else start, dtype=float)
    prior_info = np.zeros((3, 3)) if prior is None else np.asarray(prior, dtype=float)
    fail = Match(pose, np.eye(3) * 1e6, 0.0, float("inf"), False)
    if reference.tree is None or points.shape[0] < MIN_POINTS:
        return fail
    hessian = np.eye(3)
    pair_radius = max_pair
    for _ in range(iterations):
        world = transform_points(pose, points)
        paired, idx = _pairs(reference, world, transform_points(pose, origin)[0], pair_radius)
        if np.count_nonzero(paired) < MIN_POINTS:
            return fail
        p, q = points[paired], reference.points[idx[paired]]
        n = reference.normals[idx[paired]]
        w_pts = world[paired]
        r = np.einsum("ij,ij->i", n, w_pts - q)
        c, s = np.cos(pose[2]), np.sin(pose[2])
        dx = -s * p[:, 0] - c * p[:, 1]
        dy = c * p[:, 0] - s * p[:, 1]
        jac = np.column_stack([n[:, 0], n[:, 1], n[:, 0] * dx + n[:, 1] * dy])
        # Cauchy's kernel: a point paired with the wrong surface (a place the reference has not
        # seen yet, paired with the edge of what it has) pulls less the farther it is; Huber's
        # pulled with a constant force, always backwards for a robot driving into the unknown.
        w = reference.weights[idx[paired]] / (1.0 + (r / huber) ** 2)
        # Per-point variance: the robust spread of the residuals, inflated for the correlation
        # of neighbouring beams (POINT_CORRELATION), to weigh the scan against the prior.
        variance = POINT_CORRELATION * max((1.4826 * float(np.median(np.abs(r)))) ** 2, MIN_POINT_STD ** 2)
        hessian = (jac * w[:, None]).T @ jac / variance + prior_info
        offset = pose - np.asarray(guess, dtype=float)
        offset[2] = float(wrap(offset[2]))
        try:
            step = -np.linalg.solve(hessian + 1e-9 * np.eye(3),
                                    (jac * w[:, None]).T @ r / variance + prior_info @ offset)
        except np.linalg.LinAlgError:
            return fail
        pose += step
        pose[2] = float(wrap(pose[2]))
        pair_radius = max(0.5 * pair_radius, 4.0 * huber)  # tighten as it converges
        if np.hypot(step[0], step[1]) < 1e-6 and abs(step[2]) < 1e-6:
            break
    inlier = np.abs(r) <= huber
    m = int(np.count_nonzero(inlier))
    if m < MIN_POINTS or np.linalg.cond(hessian) > 1e8:
        return Match(pose, np.eye(3) * 1e6, m / points.shape[0], float("inf"), False)
    covariance = np.linalg.inv(hessian) * cov_scale
    return Match(pose, 0.5 * (covariance + covariance.T), m / points.shape[0],
                 float(np.sqrt(np.mean(r[inlier] ** 2))), True)
