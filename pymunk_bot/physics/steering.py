"""How a control body is steered so its robot follows a twist: each formula written once, compiled.

The kernels below loop over robots, reading and writing their bodies through Chipmunk's own
functions (:mod:`pymunk_bot.physics.chipmunk`), so one robot and ten thousand take the same
path and a robot gets the very same floats alone, in a fleet or as one of many copies. The
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
from pymunk_bot.physics.chipmunk import (GET_ANGLE, GET_SPIN, SET_ANCHOR, SET_ANGLE, SET_SPIN,
                                         SET_VELOCITY, get_scalar, set_scalar, set_vect)
from pymunk_bot.physics.row_table import floats_1d, floats_2d, integers_1d, integers_2d
from pymunk_bot.robots.drives.diff import advance_every_row, coast_settled_rows


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


# A robot's steering row (``steer``, floats): the twist its control body holds (NaN: none, it
# is aimed substep by substep) and the step [s] it is held for, whether its pivot's anchor is
# off the control body's centre (1.0) and its ``cog`` [m]. ``chip``: each robot's (body,
# control body, pivot joint) as Chipmunk addresses (:mod:`pymunk_bot.physics.chipmunk`).
HELD, HELD_STEP, ANCHORED, COG_X, COG_Y = 0, 3, 4, 5, 6
STEER_COLUMNS = 7
# A held robot's anchor is |u| / |omega| from the control body's centre; farther than this
# [m] (an almost straight path) it is aimed substep by substep instead.
MAX_ANCHOR = 1e6


@numba.njit(cache=True)
def aim_one(calls: np.ndarray, chip: np.ndarray, steer: np.ndarray, k: int, ux: float,
            uy: float, omega: float, h: float, h_next: float) -> None:
    """Robot ``k``'s control body velocity for the next substep, of ``h_next`` [s], after this
    one of ``h`` [s] (:func:`aim`); its anchor back at the centre, nothing held."""
    body, control = chip[k, 0], chip[k, 1]
    if steer[k, ANCHORED] != 0.0:  # from holding: the anchor back to the centre
        set_vect(calls[SET_ANCHOR], chip[k, 2], 0.0, 0.0)
        steer[k, ANCHORED] = 0.0
    steer[k, HELD] = steer[k, HELD + 1] = steer[k, HELD + 2] = steer[k, HELD_STEP] = math.nan
    vx, vy = aim(get_scalar(calls[GET_ANGLE], body), get_scalar(calls[GET_SPIN], body), ux, uy,
                 omega, h, h_next, steer[k, COG_X], steer[k, COG_Y])
    set_vect(calls[SET_VELOCITY], control, vx, vy)
    set_scalar(calls[SET_SPIN], control, omega)


@numba.njit(cache=True)
def aim_each(calls: np.ndarray, chip: np.ndarray, steer: np.ndarray, members: np.ndarray,
             ux: np.ndarray, uy: np.ndarray, omega: np.ndarray, h: float,
             h_next: np.ndarray) -> None:
    """:func:`aim_one` for robots ``members`` (their twists in the same order); ``h_next``
    [s]: each member's, or (length 1) one for all."""
    each = h_next.shape[0] > 1
    for j in range(members.shape[0]):
        aim_one(calls, chip, steer, members[j], ux[j], uy[j], omega[j], h,
                h_next[j if each else 0])


@numba.njit(cache=True)
def hold_one(calls: np.ndarray, chip: np.ndarray, steer: np.ndarray, k: int, ux: float,
             uy: float, w: float, h: float) -> bool:
    """Robot ``k`` held on its twist for a step of substeps ``h`` [s] (see
    :mod:`pymunk_bot.physics.propulsion`): a turning one by its pivot's :func:`anchor`, its
    control body spinning at omega ``w`` and headed as the robot will be at the solve; a
    straight one aimed once. False: its anchor would lie beyond MAX_ANCHOR, and it is aimed for
    this substep only."""
    body, control = chip[k, 0], chip[k, 1]
    if w == 0.0:  # a constant velocity: one aim lasts the step
        aim_one(calls, chip, steer, k, ux, uy, w, h, h)
        return True
    if (steer[k, HELD] != ux or steer[k, HELD + 1] != uy or steer[k, HELD + 2] != w
            or steer[k, HELD_STEP] != h):  # the anchor gives the chord of steps of h only
        ax, ay = anchor(ux, uy, w, h, steer[k, COG_X], steer[k, COG_Y])
        if not (abs(ax) <= MAX_ANCHOR and abs(ay) <= MAX_ANCHOR):
            aim_one(calls, chip, steer, k, ux, uy, w, h, h)
            return False
        set_vect(calls[SET_VELOCITY], control, 0.0, 0.0)
        set_scalar(calls[SET_SPIN], control, w)
        set_vect(calls[SET_ANCHOR], chip[k, 2], ax, ay)
        steer[k, ANCHORED] = 1.0
        steer[k, HELD], steer[k, HELD + 1], steer[k, HELD + 2] = ux, uy, w
        steer[k, HELD_STEP] = h
    # At each solve the control body's heading equals the robot's (both turn at omega); in
    # free space they already do, to the last bit, and the write is skipped.
    heading = (get_scalar(calls[GET_ANGLE], body)
               + (get_scalar(calls[GET_SPIN], body) - w) * h)
    if heading != get_scalar(calls[GET_ANGLE], control):
        set_scalar(calls[SET_ANGLE], control, heading)
    return True


@numba.njit(cache=True)
def hold_each(calls: np.ndarray, chip: np.ndarray, steer: np.ndarray, members: np.ndarray,
              ux: np.ndarray, uy: np.ndarray, omega: np.ndarray, steps: np.ndarray,
              aimed: np.ndarray) -> int:
    """:func:`hold_one` for robots ``members`` (their twists in the same order), each for a
    step of substeps ``steps`` [s]: each member's (robots stepping apart take one of the whole
    tick, the others substeps), or (length 1) one for all. The positions in ``members`` of
    those aimed instead are put in ``aimed``, and their count returned."""
    each = steps.shape[0] > 1
    count = 0
    for j in range(members.shape[0]):
        if not hold_one(calls, chip, steer, members[j], ux[j], uy[j], omega[j],
                        steps[j if each else 0]):
            aimed[count] = j
            count += 1
    return count


@numba.njit(cache=True)
def hold_coasting_wheels(table: np.ndarray, h: float, substeps: int) -> int:
    """A differential drive's robots in one pass: if every motor has reached its target, the
    wheels coast through ``substeps`` substeps of ``h`` [s] and the robots are held for them
    (:func:`hold_each`; returns the count of those aimed instead); else nothing is done and -1
    returned. One call, given one array, instead of the drive's and the hold's, given
    thirteen: from Python, each array costs about what one robot's work does.

    ``table`` (:class:`~pymunk_bot.physics.row_table.RowTable`), slot by slot: Chipmunk's
    calls; the steering's ``chip`` and ``steer`` rows; the drive's robots (their rows there, in
    the drive's order); the drive's ``commanded``, ``target``, ``turning``, ``travel`` and
    ``track`` (robots/drives/diff.py); its twist rows (ux, uy, omega); hold_each's scratch of
    robots aimed; a scratch of one step [s]."""
    calls, chip, steer = integers_1d(table, 0), integers_2d(table, 1), floats_2d(table, 2)
    members, aimed = integers_1d(table, 3), integers_1d(table, 10)
    twists = floats_2d(table, 9)
    ux, uy, omega = twists[0], twists[1], twists[2]
    if not coast_settled_rows(floats_2d(table, 4), floats_2d(table, 5), floats_2d(table, 6),
                              floats_2d(table, 7), floats_1d(table, 8), h * substeps, ux,
                              omega):
        return -1
    step = floats_1d(table, 11)
    step[0] = h
    return hold_each(calls, chip, steer, members, ux, uy, omega, step, aimed)


@numba.njit(cache=True)
def advance_and_aim_wheels(table: np.ndarray, h: float) -> None:
    """A differential drive's robots through one substep of ``h`` [s] while some motor still
    reaches its target: the motors advance (robots/drives/diff.py) and every robot is aimed
    for the step the table's last slot names (:func:`aim_each`). One call, given one array,
    instead of the drive's and the aim's, given thirteen. ``table``: the slots of
    :func:`hold_coasting_wheels`, then the drive's ``max_accel`` and the next step [s]."""
    calls, chip, steer = integers_1d(table, 0), integers_2d(table, 1), floats_2d(table, 2)
    twists = floats_2d(table, 9)
    ux, uy, omega = twists[0], twists[1], twists[2]
    advance_every_row(floats_2d(table, 4), floats_2d(table, 5), floats_2d(table, 6),
                      floats_2d(table, 7), floats_1d(table, 12), floats_1d(table, 8), h, ux,
                      omega)
    aim_each(calls, chip, steer, integers_1d(table, 3), ux, uy, omega, h,
             floats_1d(table, 13))
