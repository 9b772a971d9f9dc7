"""The per-agent linear program of ORCA, compiled with numba (imported lazily by orca.py).

Each agent has half-planes {v : (v - q_k) . n_k >= 0} (``n_k`` unit normals pointing into
the allowed side), the first ``hard`` of them from walls. It takes the velocity closest to
its preferred one inside all of them and within its speed limit; when they leave no room, the
velocity that violates the agent-agent half-planes least (van den Berg et al., "Reciprocal
n-body collision avoidance", ISRR 2011, section 5.2), keeping the wall half-planes.
"""
from __future__ import annotations

import math

import numba
import numpy as np

EPS = 1e-9


@numba.njit(cache=True, nogil=True)
def _on_line(q: np.ndarray, n: np.ndarray, i: int, count: int, vmax: float,
             pref_x: float, pref_y: float, maximize: bool) -> tuple[bool, float, float]:
    """Best point on the border of half-plane ``i`` that satisfies half-planes 0..i-1 and
    |v| <= vmax: closest to ``pref`` or, with ``maximize``, farthest along direction pref."""
    qx, qy = q[i, 0], q[i, 1]
    dx, dy = n[i, 1], -n[i, 0]  # along the border
    b = qx * dx + qy * dy
    disc = b * b - (qx * qx + qy * qy - vmax * vmax)
    if disc < 0.0:
        return False, 0.0, 0.0
    root = math.sqrt(disc)
    lo, hi = -b - root, -b + root
    for j in range(i):
        den = dx * n[j, 0] + dy * n[j, 1]
        num = (q[j, 0] - qx) * n[j, 0] + (q[j, 1] - qy) * n[j, 1]
        if abs(den) <= EPS:
            if num > EPS:  # parallel and outside it: no point of this border qualifies
                return False, 0.0, 0.0
            continue
        t = num / den
        if den > 0.0:
            lo = max(lo, t)
        else:
            hi = min(hi, t)
        if lo > hi:
            return False, 0.0, 0.0
    if maximize:
        t = hi if pref_x * dx + pref_y * dy > 0.0 else lo
    else:
        t = min(max((pref_x - qx) * dx + (pref_y - qy) * dy, lo), hi)
    return True, qx + t * dx, qy + t * dy


@numba.njit(cache=True, nogil=True)
def _solve(q: np.ndarray, n: np.ndarray, count: int, vmax: float, pref_x: float,
           pref_y: float, maximize: bool) -> tuple[int, float, float]:
    """Incremental 2-D LP (Seidel order = the given order). Returns (index of the first
    half-plane that could not be met, or ``count``) and the velocity so far."""
    if maximize:
        norm = math.hypot(pref_x, pref_y)
        vx, vy = pref_x / norm * vmax, pref_y / norm * vmax
    else:
        speed = math.hypot(pref_x, pref_y)
        scale = vmax / speed if speed > vmax else 1.0
        vx, vy = pref_x * scale, pref_y * scale
    for i in range(count):
        if (vx - q[i, 0]) * n[i, 0] + (vy - q[i, 1]) * n[i, 1] < -EPS:
            ok, x, y = _on_line(q, n, i, count, vmax, pref_x, pref_y, maximize)
            if not ok:
                return i, vx, vy
            vx, vy = x, y
    return count, vx, vy


@numba.njit(cache=True, nogil=True)
def _least_violation(q: np.ndarray, n: np.ndarray, count: int, hard: int, start: int,
                     vmax: float, vx: float, vy: float) -> tuple[float, float]:
    """From half-plane ``start`` on, move to the point whose largest violation of the soft
    half-planes is smallest (each step: an LP over the bisectors of equal violation)."""
    worst = 0.0
    pq = np.empty((count, 2))
    pn = np.empty((count, 2))
    for i in range(start, count):
        violation = -((vx - q[i, 0]) * n[i, 0] + (vy - q[i, 1]) * n[i, 1])
        if violation <= worst:
            continue
        m = 0
        for j in range(hard):  # wall half-planes stay as they are
            pq[m, 0], pq[m, 1], pn[m, 0], pn[m, 1] = q[j, 0], q[j, 1], n[j, 0], n[j, 1]
            m += 1
        for j in range(hard, i):
            # where j is violated no more than i: x . (n_j - n_i) >= q_j . n_j - q_i . n_i
            mx, my = n[j, 0] - n[i, 0], n[j, 1] - n[i, 1]
            norm = math.hypot(mx, my)
            if norm <= EPS:
                continue  # the same direction: j adds nothing here
            c = (q[j, 0] * n[j, 0] + q[j, 1] * n[j, 1]
                 - q[i, 0] * n[i, 0] - q[i, 1] * n[i, 1]) / norm
            pn[m, 0], pn[m, 1] = mx / norm, my / norm
            pq[m, 0], pq[m, 1] = pn[m, 0] * c, pn[m, 1] * c
            m += 1
        failed, x, y = _solve(pq, pn, m, vmax, n[i, 0], n[i, 1], True)
        if failed == m:  # else keep the last point (rounding)
            vx, vy = x, y
        worst = -((vx - q[i, 0]) * n[i, 0] + (vy - q[i, 1]) * n[i, 1])
    return vx, vy


@numba.njit(cache=True, nogil=True)
def solve_all(q: np.ndarray, n: np.ndarray, counts: np.ndarray, hard: np.ndarray,
              vmax: np.ndarray, pref: np.ndarray) -> np.ndarray:
    """New velocities (k, 2) for k agents: ``q``, ``n`` (k, L, 2) their half-planes (the
    first ``hard[a]`` from walls), ``counts`` (k,) how many, ``vmax`` (k,) [m/s], ``pref``
    (k, 2) preferred velocities [m/s]."""
    out = np.empty((q.shape[0], 2))
    for a in range(q.shape[0]):
        count = counts[a]
        failed, vx, vy = _solve(q[a], n[a], count, vmax[a], pref[a, 0], pref[a, 1], False)
        if failed < count:
            vx, vy = _least_violation(q[a], n[a], count, hard[a], failed, vmax[a], vx, vy)
        out[a, 0], out[a, 1] = vx, vy
    return out
