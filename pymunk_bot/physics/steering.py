"""How a control body is steered so its robot follows a twist: each formula written once, compiled.

The same compiled function serves one robot (called with floats, for less than the Python it
replaces) and rows of robots (the kernels below loop over it), so a robot gets the very same
floats whether it is steered alone, in a fleet or as one of many copies of a scenario. The
formulas are explained in :mod:`pymunk_bot.physics.propulsion`; a twist is (ux, uy [m/s] in the robot
frame, omega [rad/s]); ``cog`` is the body origin's offset from the centre of gravity in the body
frame [m] (a car's pose point is its rear axle).

No ``fastmath``: IEEE arithmetic in the order written, and ``math.sin``/``math.cos`` from the C
library, as Python's own.
"""
from __future__ import annotations

import math

import numba
import numpy as np

from pymunk_bot.geometry.arcs import sinc_half


@numba.njit(cache=True)
def origin_correction(cx: float, cy: float, angle: float, omega: float,
                      h: float) -> tuple[float, float]:
    """Velocity [m/s] to add so a body origin ``(cx, cy)`` away from the centre of gravity moves
    along the exact chord over ``h`` [s]: pymunk rotates the offset by the linear omega h x r,
    the body by R(omega h)."""
    c, s = math.cos(angle), math.sin(angle)
    rx, ry = -(c * cx - s * cy), -(s * cx + c * cy)  # centre -> origin, world frame
    turn = omega * h
    ct, st = math.cos(turn), math.sin(turn)
    exact_x, exact_y = (ct - 1.0) * rx - st * ry, st * rx + (ct - 1.0) * ry
    return (-turn * ry - exact_x) / h, (turn * rx - exact_y) / h


@numba.njit(cache=True)
def aim(angle: float, spin: float, ux: float, uy: float, omega: float, h: float, h_next: float,
        cx: float, cy: float) -> tuple[float, float]:
    """The control body's velocity [m/s] for the next substep, of ``h_next`` [s], after this one
    of ``h`` [s], for a robot at ``angle`` [rad] turning at ``spin`` [rad/s]: along the chord of
    the next substep's arc, at the heading half-way through it."""
    heading = angle + spin * h + 0.5 * omega * h_next
    chord = sinc_half(omega * h_next)
    c, s = math.cos(heading), math.sin(heading)
    vx, vy = (ux * c - uy * s) * chord, (ux * s + uy * c) * chord
    if cx != 0.0 or cy != 0.0:
        dvx, dvy = origin_correction(cx, cy, angle + spin * h, omega, h_next)
        vx, vy = vx + dvx, vy + dvy
    return vx, vy


@numba.njit(cache=True)
def anchor(ux: float, uy: float, omega: float, h: float, cx: float,
           cy: float) -> tuple[float, float]:
    """Where on a control body spinning at ``omega`` [rad/s] (not 0) the pivot's anchor [m] gives
    the robot the chord velocity of the twist, for substeps of ``h`` [s]: the chord velocity in
    the robot frame at the start of a substep's solve is omega x anchor, so the anchor is that
    velocity turned back a quarter turn, / omega."""
    chord = sinc_half(omega * h)
    c, s = math.cos(0.5 * omega * h), math.sin(0.5 * omega * h)
    wx, wy = (ux * c - uy * s) * chord, (ux * s + uy * c) * chord
    if cx != 0.0 or cy != 0.0:
        dvx, dvy = origin_correction(cx, cy, 0.0, omega, h)
        wx, wy = wx + dvx, wy + dvy
    return wy / omega, -wx / omega


@numba.njit(cache=True)
def aim_rows(state: np.ndarray, robot_rows: np.ndarray, control_rows: np.ndarray,
             members: np.ndarray, ux: np.ndarray, uy: np.ndarray, omega: np.ndarray,
             h: np.ndarray, h_next: np.ndarray, cog: np.ndarray, out: np.ndarray) -> None:
    """:func:`aim` for robots ``members`` (their twists, steps ``h`` and next steps ``h_next``
    [s] in the same order; ``h`` or ``h_next`` of length 1: the same for all), from the
    bodies' ``state`` rows (angle, vx, vy, omega) in pymunk's body order: each control body's
    (vx, vy, omega) into ``out`` (rows in the same order), every other body's as it is."""
    for r in range(state.shape[0]):
        out[r, 0], out[r, 1], out[r, 2] = state[r, 1], state[r, 2], state[r, 3]
    each, each_next = h.shape[0] > 1, h_next.shape[0] > 1
    for j in range(members.shape[0]):
        k = members[j]
        r = robot_rows[k]
        vx, vy = aim(state[r, 0], state[r, 3], ux[j], uy[j], omega[j], h[j if each else 0],
                     h_next[j if each_next else 0], cog[k, 0], cog[k, 1])
        row = control_rows[k]
        out[row, 0] = vx
        out[row, 1] = vy
        out[row, 2] = omega[j]


@numba.njit(cache=True)
def hold_rows(state: np.ndarray, robot_rows: np.ndarray, control_rows: np.ndarray,
              ux: np.ndarray, uy: np.ndarray, omega: np.ndarray, h: np.ndarray, cog: np.ndarray,
              max_anchor: float, anchors: np.ndarray, out: np.ndarray, held: np.ndarray,
              changed: np.ndarray) -> bool:
    """Every robot held for a step of substeps ``h`` [s] (a row: its own; of length 1: the
    same for all): a turning one by its pivot's
    :func:`anchor` (into ``anchors``; its control body spinning at omega, headed as the robot
    will be at the solve), a straight one aimed once. Control bodies' (angle, vx, vy, omega) into
    ``out`` (rows in pymunk's body order); ``held`` (n, 3), the twists held before (NaN: none),
    becomes these, and ``changed`` says whose differ. False if some anchor would lie beyond
    ``max_anchor`` [m] (``out`` is then incomplete, ``held`` untouched)."""
    each = h.shape[0] > 1
    for k in range(robot_rows.shape[0]):
        r, row = robot_rows[k], control_rows[k]
        angle, spin = state[r, 0], state[r, 3]
        hk = h[k if each else 0]
        if omega[k] != 0.0:
            ax, ay = anchor(ux[k], uy[k], omega[k], hk, cog[k, 0], cog[k, 1])
            if not (abs(ax) <= max_anchor and abs(ay) <= max_anchor):
                return False
            anchors[k, 0], anchors[k, 1] = ax, ay
            out[row, 0] = angle + (spin - omega[k]) * hk
            out[row, 1], out[row, 2] = 0.0, 0.0
        else:
            anchors[k, 0], anchors[k, 1] = 0.0, 0.0
            out[row, 1], out[row, 2] = aim(angle, spin, ux[k], uy[k], 0.0, hk, hk,
                                           cog[k, 0], cog[k, 1])
        out[row, 3] = omega[k]
    for k in range(robot_rows.shape[0]):
        differs = held[k, 0] != ux[k] or held[k, 1] != uy[k] or held[k, 2] != omega[k]
        changed[k] = differs
        if differs:
            held[k, 0], held[k, 1], held[k, 2] = ux[k], uy[k], omega[k]
    return True
