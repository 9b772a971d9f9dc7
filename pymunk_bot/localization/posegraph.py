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
             tolerance: float = 1e-6) -> tuple[np.ndarray, float]:
    """Optimized poses (n, 3) and the final robust cost (sum of rho(e^T omega e))."""
    x = np.array(poses, dtype=float)
    n = x.shape[0]
    if not edges:
        return x, 0.0
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
        h = coo_matrix((vals, (rows, cols)), shape=(3 * n, 3 * n)).tocsc()
        dx = spsolve(h, -grad).reshape(n, 3)
        x += dx
        x[:, 2] = wrap(x[:, 2])
        if np.abs(dx).max() < tolerance:
            break
    chi2 = _chi2(x, ii, jj, z, omega)
    scale2 = np.where(robust > 0.0, robust, 1.0) ** 2
    cost = float(np.sum(np.where(robust > 0.0, scale2 * np.log1p(chi2 / scale2), chi2)))
    return x, cost


def final_weights(poses: np.ndarray, edges: list[Edge]) -> np.ndarray:
    """Each edge's IRLS weight at ``poses`` (1: fully believed; near 0: overruled)."""
    if not edges:
        return np.zeros(0)
    ii, jj, z, omega, robust = _stacked(edges)
    return edge_weights(_chi2(np.asarray(poses, dtype=float), ii, jj, z, omega), robust)


def relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The measurement z of an edge a -> b."""
    return between(a, b)
