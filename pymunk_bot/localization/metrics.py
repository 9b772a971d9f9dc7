"""How good a pose estimate is: per-run error block, ATE and RPE of a trajectory.

Definitions follow evo (Grupp, github.com/MichaelGrupp/evo), reduced to SE(2):

- **ATE** (evo's APE, translation part): for time-matched samples ``P_i`` (estimate) and ``Q_i``
  (ground truth), ``E_i = Q_i^-1 P_i`` and the error is ``|trans(E_i)| = |p_i - q_i|``; reported
  as RMSE, mean, median, max and std over the samples. No alignment by default: estimates here
  live in the world frame already (``align=True`` first applies the least-squares rigid motion,
  Umeyama without scale, as ``evo_ape -a``).
- **RPE** (evo's RPE, translation and rotation parts): for pairs ``(i, j)`` where ``j`` is the
  first sample at least ``delta`` further along (metres of true path, evo's ``--delta_unit m``;
  or samples, ``unit="frames"``), ``E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)``; the error is
  ``|trans(E_ij)|`` [m] and ``|angle(E_ij)|`` [rad]. It measures drift per ``delta``,
  independent of where the error started.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .se2 import between, wrap


def _check(truth: np.ndarray, estimate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    truth, estimate = np.asarray(truth, dtype=float), np.asarray(estimate, dtype=float)
    if truth.shape != estimate.shape or truth.ndim != 2 or truth.shape[1] != 3 or truth.shape[0] == 0:
        raise ValueError(f"need matching (n, 3) pose arrays (got {truth.shape} and {estimate.shape})")
    return truth, estimate


def error_block(truth: np.ndarray, estimate: np.ndarray) -> dict[str, float]:
    """The result JSON's ``localization`` block: position errors [m] and heading RMSE [rad]."""
    truth, estimate = _check(truth, estimate)
    err = np.hypot(*(estimate[:, :2] - truth[:, :2]).T)
    heading = wrap(estimate[:, 2] - truth[:, 2])
    return {"rmse": float(np.sqrt(np.mean(err ** 2))), "max_error": float(err.max()),
            "final_error": float(err[-1]), "heading_rmse": float(np.sqrt(np.mean(heading ** 2)))}


def _stats(values: np.ndarray) -> dict[str, float]:
    return {"rmse": float(np.sqrt(np.mean(values ** 2))), "mean": float(values.mean()),
            "median": float(np.median(values)), "max": float(values.max()),
            "std": float(values.std())}


def align_rigid(truth: np.ndarray, estimate: np.ndarray) -> np.ndarray:
    """The estimate moved by the rigid motion that best fits its positions to the truth's."""
    p, q = estimate[:, :2], truth[:, :2]
    mp, mq = p.mean(axis=0), q.mean(axis=0)
    u, _, vt = np.linalg.svd((q - mq).T @ (p - mp))
    d = np.sign(np.linalg.det(u @ vt))
    r = u @ np.diag([1.0, d]) @ vt
    moved = estimate.copy()
    moved[:, :2] = (p - mp) @ r.T + mq
    moved[:, 2] = wrap(estimate[:, 2] + np.arctan2(r[1, 0], r[0, 0]))
    return moved


def ate(truth: np.ndarray, estimate: np.ndarray, align: bool = False) -> dict[str, float]:
    """Absolute trajectory error [m] (evo APE, translation part): rmse, mean, median, max, std."""
    truth, estimate = _check(truth, estimate)
    if align:
        estimate = align_rigid(truth, estimate)
    return _stats(np.hypot(*(estimate[:, :2] - truth[:, :2]).T))


def rpe(truth: np.ndarray, estimate: np.ndarray, delta: float = 1.0,
        unit: str = "m") -> dict[str, Any]:
    """Relative pose error over ``delta`` metres of true path (or ``delta`` samples, "frames").

    Returns {"trans": stats [m], "rot": stats [rad], "pairs": count}; empty stats when the
    trajectory is shorter than ``delta``.
    """
    truth, estimate = _check(truth, estimate)
    if unit == "m":
        travelled = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(truth[:, :2], axis=0).T))])
        j = np.searchsorted(travelled, travelled + delta)
    elif unit == "frames":
        j = np.arange(truth.shape[0]) + int(delta)
    else:
        raise ValueError(f"unit must be 'm' or 'frames' (got {unit!r})")
    i = np.flatnonzero(j < truth.shape[0])
    j = j[i]
    if i.size == 0:
        return {"trans": {}, "rot": {}, "pairs": 0}
    rel_truth = between(truth[i], truth[j])
    rel_est = between(estimate[i], estimate[j])
    err = between(rel_truth, rel_est)
    return {"trans": _stats(np.hypot(err[:, 0], err[:, 1])), "rot": _stats(np.abs(err[:, 2])),
            "pairs": int(i.size)}


def map_scores(built, truth, tolerance: float | None = None) -> dict[str, float]:
    """Precision and recall of a built occupancy grid's occupied cells against the true one.

    precision: fraction of cells ``built`` marks occupied that lie within ``tolerance`` [m]
    (default: one cell of ``truth``) of a truly occupied cell; recall: fraction of the true
    *surface* cells (occupied cells next to a free one) that have a built occupied cell within
    ``tolerance``, counted only where the built map has seen anything nearby.
    """
    from scipy.ndimage import binary_erosion, distance_transform_edt

    tol = truth.resolution if tolerance is None else float(tolerance)
    true_occ = truth.occupied()
    built_occ = built.occupied()
    if not built_occ.any():
        return {"precision": 0.0, "recall": 0.0, "occupied_cells": 0}
    to_true = distance_transform_edt(~true_occ) * truth.resolution
    xs, ys = built.cell_centers()
    rows, cols = np.nonzero(built_occ)
    r, c = truth.cell_of(np.stack([xs[cols], ys[rows]], axis=-1))
    inside = truth.inside(r, c)
    near = np.zeros(rows.size, dtype=bool)
    near[inside] = to_true[r[inside], c[inside]] <= tol + 1e-9
    precision = float(near.mean())
    surface = true_occ & ~binary_erosion(true_occ, border_value=1)
    to_built = distance_transform_edt(~built_occ) * built.resolution
    seen = ~built.unknown()
    txs, tys = truth.cell_centers()
    sr, sc = np.nonzero(surface)
    br, bc = built.cell_of(np.stack([txs[sc], tys[sr]], axis=-1))
    ok = built.inside(br, bc)
    br, bc = br[ok], bc[ok]
    # a surface cell counts when the built map saw within 3 cells of it
    seen_near = distance_transform_edt(~seen) * built.resolution <= 3 * built.resolution
    counted = seen_near[br, bc]
    recall = float((to_built[br, bc][counted] <= tol + 1e-9).mean()) if counted.any() else 0.0
    return {"precision": precision, "recall": recall, "occupied_cells": int(rows.size)}
