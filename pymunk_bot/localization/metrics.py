"""How good a pose estimate is: per-run error block, ATE and RPE of a trajectory.

Definitions follow evo (Grupp, github.com/MichaelGrupp/evo), reduced to SE(2):

- **ATE** (evo's APE, translation part): for time-matched samples ``P_i`` (estimate) and ``Q_i``
  (ground truth), ``E_i = Q_i^-1 P_i`` and the error is ``|trans(E_i)| = |p_i - q_i|``; reported
  as RMSE, mean, median, max and std over the samples. No alignment by default: estimates here
  live in the world frame already (``align=True`` first applies the least-squares rigid motion,
  Umeyama without scale, as ``evo_ape -a``).
- **RPE** (evo's RPE, translation and rotation parts): for pairs ``(i, j)`` ``delta`` apart,
  ``E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)``; the error is ``|trans(E_ij)|`` [m] and
  ``|angle(E_ij)|`` [rad]. It measures drift per ``delta``, independent of where the error
  started. The pairs are evo's: ``delta`` metres of path (``--delta_unit m``) or samples
  (``unit="frames"``), consecutive (the path cut into ``delta`` pieces) or, with
  ``all_pairs``, every sample paired with the one nearest ``delta`` further on (within 10 %);
  the path is the estimate's, as evo's default (``pairs_from="truth"``: evo's
  ``--pairs_from_reference``). tests/localization/test_trajectory_out.py checks the figures
  against evo's on the same files.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from pymunk_bot.localization.se2 import between, wrap


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


def _path_pairs(path: np.ndarray, delta: float, all_pairs: bool) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``delta`` metres of ``path`` apart, as evo's ``filter_pairs_by_path``."""
    steps = np.hypot(*np.diff(path[:, :2], axis=0).T)
    if all_pairs:  # each i with the later sample whose distance along is nearest delta
        along = np.concatenate([[0.0], np.cumsum(steps)])
        n = along.size
        i = np.arange(n - 1)
        target = along[i] + delta
        after = np.searchsorted(along, target, side="left")  # first at or beyond delta
        before = np.maximum(after - 1, i + 1)  # the last short of it (not i itself)
        before = np.searchsorted(along, along[before], side="left").clip(i + 1)  # its first tie
        after_ok = after < n
        gap_after = np.where(after_ok, np.abs(along[np.minimum(after, n - 1)] - target), np.inf)
        gap_before = np.abs(along[before] - target)
        j = np.where(gap_before <= gap_after, before, after)
        keep = np.minimum(gap_before, gap_after) <= 0.1 * delta
        return i[keep], j[keep]
    ids, travelled = [0], 0.0  # the path cut into pieces of at least delta
    for k, step in enumerate(steps.tolist(), start=1):
        travelled += step
        if travelled >= delta:
            ids.append(k)
            travelled = 0.0
    cut = np.asarray(ids)
    return cut[:-1], cut[1:]


def rpe(truth: np.ndarray, estimate: np.ndarray, delta: float = 1.0, unit: str = "m",
        all_pairs: bool = False, pairs_from: str = "estimate") -> dict[str, Any]:
    """Relative pose error over ``delta`` metres of path (or ``delta`` samples, "frames").

    Returns {"trans": stats [m], "rot": stats [rad], "pairs": count}; empty stats when the
    trajectory is shorter than ``delta``.
    """
    truth, estimate = _check(truth, estimate)
    if pairs_from not in ("estimate", "truth"):
        raise ValueError(f"pairs_from must be 'estimate' or 'truth' (got {pairs_from!r})")
    if unit == "m":
        if not delta > 0:
            raise ValueError(f"delta must be > 0 m (got {delta!r})")
        i, j = _path_pairs(estimate if pairs_from == "estimate" else truth, float(delta), all_pairs)
    elif unit == "frames":
        step = int(delta)
        if step != delta or step < 1:
            raise ValueError(f"delta must be a whole number of frames >= 1 (got {delta!r})")
        n = truth.shape[0]
        if all_pairs:
            i = np.arange(max(n - step, 0))
            j = i + step
        else:
            cut = np.arange(0, n, step)
            i, j = cut[:-1], cut[1:]
    else:
        raise ValueError(f"unit must be 'm' or 'frames' (got {unit!r})")
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


FALSE_CLOSURE_OFFSET = 0.2  # [m] a loop closure off the truth by more than this is false
FALSE_CLOSURE_ANGLE = np.deg2rad(3.0)  # [rad] ... or by more than this


def closure_errors(old: np.ndarray, new: np.ndarray, relative: np.ndarray,
                   truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far each loop closure's measured pose of keyframe ``new`` in keyframe ``old``'s frame
    (``relative``, (k, 3)) is off the true one, from ``truth`` (n, 3: each keyframe's true
    pose): position [m] and heading [rad] errors, (k,) each."""
    old, new = np.asarray(old, dtype=np.intp), np.asarray(new, dtype=np.intp)
    if old.size == 0:
        return np.zeros(0), np.zeros(0)
    err = between(between(truth[old], truth[new]), np.asarray(relative, dtype=float).reshape(-1, 3))
    return np.hypot(err[:, 0], err[:, 1]), np.abs(wrap(err[:, 2]))


def false_closures(old: np.ndarray, new: np.ndarray, relative: np.ndarray,
                   truth: np.ndarray) -> int:
    """Loop closures off the truth by more than FALSE_CLOSURE_OFFSET or FALSE_CLOSURE_ANGLE."""
    position, heading = closure_errors(old, new, relative, truth)
    return int(np.count_nonzero((position > FALSE_CLOSURE_OFFSET) | (heading > FALSE_CLOSURE_ANGLE)))
