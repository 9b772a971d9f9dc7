"""A 2D pose graph solved by sparse Gauss-Newton (Grisetti et al., "A tutorial on graph-based SLAM").

Nodes are poses x_i = [x, y, theta]; an edge (i, j, z, omega) says "from x_i, x_j was seen at
relative pose z" with information matrix omega (3x3). The error of an edge is
e_ij = z^-1 (+) (x_i^-1 (+) x_j), and the solver minimises sum e^T omega e with the first node
held fixed (the graph's frame is the world's: SLAM starts at the true start pose).
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
    information: np.ndarray  # 3x3


def _edge_terms(xi: np.ndarray, xj: np.ndarray, z: np.ndarray):
    """Error and Jacobians (A = de/dxi, B = de/dxj) of one edge."""
    ci, si = np.cos(xi[2]), np.sin(xi[2])
    cz, sz = np.cos(z[2]), np.sin(z[2])
    ri_t = np.array([[ci, si], [-si, ci]])
    rz_t = np.array([[cz, sz], [-sz, cz]])
    dri_t = np.array([[-si, ci], [-ci, -si]])
    dt = xj[:2] - xi[:2]
    e = np.empty(3)
    e[:2] = rz_t @ (ri_t @ dt - z[:2])
    e[2] = wrap(xj[2] - xi[2] - z[2])
    a = np.zeros((3, 3))
    b = np.zeros((3, 3))
    a[:2, :2] = -rz_t @ ri_t
    a[:2, 2] = rz_t @ dri_t @ dt
    a[2, 2] = -1.0
    b[:2, :2] = rz_t @ ri_t
    b[2, 2] = 1.0
    return e, a, b


def optimize(poses: np.ndarray, edges: list[Edge], iterations: int = 10,
             tolerance: float = 1e-6) -> tuple[np.ndarray, float]:
    """Optimized poses (n, 3) and the final chi^2 (sum of e^T omega e)."""
    x = np.array(poses, dtype=float)
    n = x.shape[0]
    chi2 = 0.0
    for _ in range(iterations):
        rows, cols, vals = [], [], []
        grad = np.zeros(3 * n)
        chi2 = 0.0
        for edge in edges:
            e, a, b = _edge_terms(x[edge.i], x[edge.j], edge.z)
            om = edge.information
            chi2 += float(e @ om @ e)
            blocks = ((edge.i, edge.i, a.T @ om @ a), (edge.i, edge.j, a.T @ om @ b),
                      (edge.j, edge.i, b.T @ om @ a), (edge.j, edge.j, b.T @ om @ b))
            for bi, bj, block in blocks:
                r, c = np.meshgrid(np.arange(3) + 3 * bi, np.arange(3) + 3 * bj, indexing="ij")
                rows.append(r.ravel())
                cols.append(c.ravel())
                vals.append(block.ravel())
            grad[3 * edge.i:3 * edge.i + 3] += a.T @ om @ e
            grad[3 * edge.j:3 * edge.j + 3] += b.T @ om @ e
        rows.append(np.arange(3))
        cols.append(np.arange(3))
        vals.append(np.full(3, ANCHOR))
        h = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(3 * n, 3 * n)).tocsc()
        dx = spsolve(h, -grad).reshape(n, 3)
        x += dx
        x[:, 2] = wrap(x[:, 2])
        if np.abs(dx).max() < tolerance:
            break
    return x, chi2


def relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The measurement z of an edge a -> b."""
    return between(a, b)
