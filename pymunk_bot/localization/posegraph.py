"""A 2D pose graph solved by sparse Gauss-Newton (Grisetti et al., "A tutorial on graph-based SLAM").

Nodes are poses x_i = [x, y, theta]; an edge (i, j, z, omega) says "from x_i, x_j was seen at
relative pose z" with information matrix omega (3x3). The error of an edge is
e_ij = z^-1 (+) (x_i^-1 (+) x_j), and the solver minimises sum rho(e^T omega e) with the first
node held fixed (the graph's frame is the world's: SLAM starts at the true start pose).

rho is the plain square for an edge whose ``robust`` scale is 0 (the front end's chain) and
Cauchy's kernel rho(s) = c^2 log(1 + s / c^2) for a loop closure with ``robust`` = c [chi, the
square root of e^T omega e]: solved by iteratively reweighted least squares, each edge's
information scaled by 1 / (1 + s / c^2) at the current poses. A closure that the rest of the
graph contradicts by many of its own standard deviations then weighs next to nothing, so one
wrong closure cannot bend the map; a right one agrees with the chain once the chain has given
way, and its weight returns to about 1.

Wall landmarks (walls.py) add a scalar node per landmark, its direction phi in the world
(modulo pi), and a factor per observation: keyframe i saw the wall at direction d in its own
frame, error e = (theta_i + d - phi) wrapped to half a turn, under Cauchy's kernel.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve

from pymunk_bot.localization.se2 import between, wrap

ANCHOR = 1e9  # information of the prior that pins the first node


@dataclass(frozen=True)
class Edge:
    i: int
    j: int
    z: np.ndarray  # measured pose of j in i's frame [x, y, theta]
    information: np.ndarray  # 3x3, of the error: x, y in j's frame (edge_information)
    robust: float = 0.0  # Cauchy kernel scale [chi]; 0: a plain least-squares edge


@dataclass(frozen=True)
class WallFactors:
    """Keyframes' observations of wall landmarks (walls.py), one entry per observation."""

    node: np.ndarray  # (k,) the keyframe that saw it
    landmark: np.ndarray  # (k,) which landmark, 0 .. m-1
    direction: np.ndarray  # (k,) [rad] the wall's direction in the keyframe's frame
    information: np.ndarray  # (k,) [1/rad^2] of that direction
    start: np.ndarray  # (m,) [rad] each landmark's world direction to start from
    robust: float  # Cauchy kernel scale [chi]


def _wall_errors(x: np.ndarray, phi: np.ndarray, walls: WallFactors) -> np.ndarray:
    """Each wall observation's error [rad]: the keyframe's heading plus the seen direction,
    less the landmark's, modulo pi."""
    e = x[walls.node, 2] + walls.direction - phi[walls.landmark]
    return (e + 0.5 * np.pi) % np.pi - 0.5 * np.pi


def edge_information(world_covariance: np.ndarray, heading: float) -> np.ndarray:
    """The information matrix (3x3) of an edge into a node at ``heading`` [rad] whose pose was
    measured with ``world_covariance`` (3x3, world frame, as a scan match gives it): the edge's
    error is in that node's frame (edge_terms), so the covariance is turned into it first.
    (Taken as it was, an aisle along the world's y axis was held along the aisle and left
    loose across it.)"""
    c, s = np.cos(heading), np.sin(heading)
    to_node = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # world -> node frame
    covariance = to_node @ np.asarray(world_covariance, dtype=float) @ to_node.T
    return np.linalg.inv(0.5 * (covariance + covariance.T))


def edge_terms(xi: np.ndarray, xj: np.ndarray, z: np.ndarray):
    """Errors (m, 3) and Jacobians A = de/dxi, B = de/dxj (m, 3, 3) of m edges at once
    (``xi``, ``xj``, ``z``: (m, 3))."""
    ci, si = np.cos(xi[:, 2]), np.sin(xi[:, 2])
    cz, sz = np.cos(z[:, 2]), np.sin(z[:, 2])
    ri_t = np.stack([np.stack([ci, si], -1), np.stack([-si, ci], -1)], -2)  # R_i^T
    rz_t = np.stack([np.stack([cz, sz], -1), np.stack([-sz, cz], -1)], -2)
    dri_t = np.stack([np.stack([-si, ci], -1), np.stack([-ci, -si], -1)], -2)  # d R_i^T / d theta
    dt = xj[:, :2] - xi[:, :2]
    m = xi.shape[0]
    e = np.empty((m, 3))
    e[:, :2] = np.einsum("mab,mb->ma", rz_t, np.einsum("mab,mb->ma", ri_t, dt) - z[:, :2])
    e[:, 2] = wrap(xj[:, 2] - xi[:, 2] - z[:, 2])
    rot = rz_t @ ri_t
    a = np.zeros((m, 3, 3))
    b = np.zeros((m, 3, 3))
    a[:, :2, :2] = -rot
    a[:, :2, 2] = np.einsum("mab,mb->ma", rz_t @ dri_t, dt)
    a[:, 2, 2] = -1.0
    b[:, :2, :2] = rot
    b[:, 2, 2] = 1.0
    return e, a, b


def edge_weights(chi2: np.ndarray, robust: np.ndarray) -> np.ndarray:
    """IRLS weights of edges with these chi^2 values: 1 for plain edges (``robust`` 0),
    Cauchy's 1 / (1 + chi^2 / c^2) for robust ones."""
    scale2 = np.where(robust > 0.0, robust, 1.0) ** 2
    return np.where(robust > 0.0, 1.0 / (1.0 + chi2 / scale2), 1.0)


def _stacked(edges: list[Edge]):
    """The edges as arrays: i, j (m,), z (m, 3), information (m, 3, 3), robust scale (m,)."""
    return (np.array([edge.i for edge in edges], dtype=np.intp),
            np.array([edge.j for edge in edges], dtype=np.intp),
            np.array([edge.z for edge in edges], dtype=float).reshape(-1, 3),
            np.array([edge.information for edge in edges], dtype=float).reshape(-1, 3, 3),
            np.array([edge.robust for edge in edges], dtype=float))


def _chi2(x: np.ndarray, ii, jj, z, omega) -> np.ndarray:
    e, _, _ = edge_terms(x[ii], x[jj], z)
    return np.einsum("ma,mab,mb->m", e, omega, e)


def optimize(poses: np.ndarray, edges: list[Edge], iterations: int = 10,
             tolerance: float = 1e-6, walls: WallFactors | None = None) -> tuple[np.ndarray, float]:
    """Optimized poses (n, 3) and the final robust cost (sum of rho(e^T omega e)); ``walls``:
    observations of wall landmarks, whose directions are solved for with the poses."""
    x = np.array(poses, dtype=float)
    n = x.shape[0]
    if not edges:
        return x, 0.0
    m = 0 if walls is None else int(walls.start.size)
    phi = np.zeros(0) if walls is None else np.array(walls.start, dtype=float)
    ii, jj, z, omega, robust = _stacked(edges)
    # sparse indices of each edge's four 3x3 blocks (ii, ij, ji, jj), fixed over iterations
    r3, c3 = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    block_rows = [3 * p[:, None, None] + r3 for p in (ii, ii, jj, jj)]
    block_cols = [3 * q[:, None, None] + c3 for q in (ii, jj, ii, jj)]
    rows = np.concatenate([b.ravel() for b in block_rows] + [np.arange(3)])
    cols = np.concatenate([b.ravel() for b in block_cols] + [np.arange(3)])
    for _ in range(iterations):
        e, a, b = edge_terms(x[ii], x[jj], z)
        chi2 = np.einsum("ma,mab,mb->m", e, omega, e)
        weight = edge_weights(chi2, robust)
        om = omega * weight[:, None, None]
        at_om, bt_om = np.transpose(a, (0, 2, 1)) @ om, np.transpose(b, (0, 2, 1)) @ om
        vals = np.concatenate([(at_om @ a).ravel(), (at_om @ b).ravel(), (bt_om @ a).ravel(),
                               (bt_om @ b).ravel(), np.full(3, ANCHOR)])
        grad = np.zeros(3 * n)
        for node, part in ((ii, np.einsum("mab,mb->ma", at_om, e)),
                           (jj, np.einsum("mab,mb->ma", bt_om, e))):
            np.add.at(grad, (3 * node[:, None] + np.arange(3)).ravel(), part.ravel())
        grad = np.concatenate([grad, np.zeros(m)])
        wall_rows, wall_cols, wall_vals = _wall_terms(x, phi, walls, grad)
        h = coo_matrix((np.concatenate([vals, wall_vals]),
                        (np.concatenate([rows, wall_rows]), np.concatenate([cols, wall_cols]))),
                       shape=(3 * n + m, 3 * n + m)).tocsc()
        step = spsolve(h, -grad)
        dx = step[:3 * n].reshape(n, 3)
        x += dx
        x[:, 2] = wrap(x[:, 2])
        phi += step[3 * n:]
        if np.abs(step).max() < tolerance:
            break
    chi2 = _chi2(x, ii, jj, z, omega)
    scale2 = np.where(robust > 0.0, robust, 1.0) ** 2
    cost = float(np.sum(np.where(robust > 0.0, scale2 * np.log1p(chi2 / scale2), chi2)))
    if walls is not None:
        wall_chi2 = walls.information * _wall_errors(x, phi, walls) ** 2
        cost += float(np.sum(walls.robust ** 2 * np.log1p(wall_chi2 / walls.robust ** 2)))
    return x, cost


def _wall_terms(x: np.ndarray, phi: np.ndarray, walls: WallFactors | None, grad: np.ndarray):
    """The wall factors' Hessian entries (rows, cols, values) at ``x`` and landmark
    directions ``phi``; their gradient is added to ``grad`` (length 3 n + m) in place.
    d e / d theta_i = 1, d e / d phi = -1."""
    if walls is None:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp), np.zeros(0)
    e = _wall_errors(x, phi, walls)
    w = walls.information * edge_weights(walls.information * e ** 2,
                                         np.full(e.size, walls.robust))
    theta = 3 * walls.node + 2
    lm = 3 * x.shape[0] + walls.landmark
    np.add.at(grad, theta, w * e)
    np.add.at(grad, lm, -w * e)
    rows = np.concatenate([theta, theta, lm, lm])
    cols = np.concatenate([theta, lm, theta, lm])
    return rows, cols, np.concatenate([w, -w, -w, w])


def final_weights(poses: np.ndarray, edges: list[Edge]) -> np.ndarray:
    """Each edge's IRLS weight at ``poses`` (1: fully believed; near 0: overruled)."""
    if not edges:
        return np.zeros(0)
    ii, jj, z, omega, robust = _stacked(edges)
    return edge_weights(_chi2(np.asarray(poses, dtype=float), ii, jj, z, omega), robust)


def relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The measurement z of an edge a -> b."""
    return between(a, b)
