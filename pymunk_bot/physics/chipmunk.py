"""Chipmunk's own body and joint accessors, called from compiled code.

pymunk's properties reach Chipmunk through Python (a few hundred nanoseconds each); a compiled
loop that calls Chipmunk's C functions itself pays a few nanoseconds a call, so one loop
serves one robot and ten thousand alike (the steering of :mod:`pymunk_bot.physics.propulsion`).
The functions are Chipmunk's public API (``cpBodyGetAngle``, ``cpBodySetVelocity``, ...), found
through ``pymunk.ffi``; their addresses are passed to the kernels in one array, :data:`CALLS`,
so a kernel's cache stays valid in every process. A body or joint is passed as its address
(:func:`addresses`), valid while the pymunk object lives.

``cpVect`` (two doubles) crosses by value: in two floating-point registers on x86-64 (System V)
and arm64, exactly as two doubles do; Windows x64 passes and returns it through memory, which
the calls below do there (numba, and so this module, runs on 64-bit platforms only).
``tests/test_chipmunk.py`` checks every accessor against pymunk's properties.
"""
from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Sequence

import numba
import numpy as np
import pymunk
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

# Windows x64 passes a 16-byte struct by reference and returns one through a hidden pointer.
_BY_REFERENCE = sys.platform == "win32"

# The accessors, in the order of their indices in CALLS.
_NAMES = ("cpBodyGetAngle", "cpBodyGetAngularVelocity", "cpBodySetAngle",
          "cpBodySetAngularVelocity", "cpBodyGetPosition", "cpBodyGetVelocity",
          "cpBodySetVelocity", "cpPivotJointSetAnchorA")
GET_ANGLE, GET_SPIN, SET_ANGLE, SET_SPIN, GET_POSITION, GET_VELOCITY, SET_VELOCITY, \
    SET_ANCHOR = range(len(_NAMES))
# Their addresses (this process's: passed to kernels as an argument, never compiled in).
CALLS = np.array([int(pymunk.ffi.cast("uintptr_t", pymunk.ffi.addressof(pymunk.cp, name)))
                  for name in _NAMES], dtype=np.intp)


def addresses(objects: Sequence[pymunk.Body | pymunk.Constraint]) -> np.ndarray:
    """The Chipmunk addresses of pymunk bodies or constraints (valid while each lives)."""
    handles = [o._body if isinstance(o, pymunk.Body) else o._constraint for o in objects]
    return np.array([int(pymunk.ffi.cast("uintptr_t", h)) for h in handles], dtype=np.intp)


_DOUBLE = ir.DoubleType()
_VECT = ir.LiteralStructType([_DOUBLE, _DOUBLE])
_POINTER = ir.IntType(8).as_pointer()


def _function(builder: ir.IRBuilder, address: ir.Value, result: ir.Type,
              arguments: list[ir.Type]) -> ir.Value:
    """The C function at ``address`` (an integer), as a callable of this type."""
    return builder.inttoptr(address, ir.FunctionType(result, arguments).as_pointer())


@intrinsic
def _get_scalar(typingctx, call, address):  # type: ignore[no-untyped-def]
    """``double f(cpBody *)`` at ``call`` for the body at ``address``."""
    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        f = _function(builder, args[0], _DOUBLE, [_POINTER])
        return builder.call(f, [builder.inttoptr(args[1], _POINTER)])
    return types.float64(types.intp, types.intp), codegen


@intrinsic
def _set_scalar(typingctx, call, address, value):  # type: ignore[no-untyped-def]
    """``void f(cpBody *, double)`` at ``call``."""
    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        f = _function(builder, args[0], ir.VoidType(), [_POINTER, _DOUBLE])
        builder.call(f, [builder.inttoptr(args[1], _POINTER), args[2]])
        return context.get_dummy_value()
    return types.void(types.intp, types.intp, types.float64), codegen


@intrinsic
def _get_vect(typingctx, call, address):  # type: ignore[no-untyped-def]
    """``cpVect f(cpBody *)`` at ``call``, as (x, y)."""
    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        body = builder.inttoptr(args[1], _POINTER)
        if _BY_REFERENCE:
            out = builder.alloca(_VECT)
            f = _function(builder, args[0], _VECT.as_pointer(), [_VECT.as_pointer(), _POINTER])
            builder.call(f, [out, body])
            vect = builder.load(out)
        else:
            vect = builder.call(_function(builder, args[0], _VECT, [_POINTER]), [body])
        x, y = builder.extract_value(vect, 0), builder.extract_value(vect, 1)
        return context.make_tuple(builder, signature.return_type, (x, y))
    return types.UniTuple(types.float64, 2)(types.intp, types.intp), codegen


@intrinsic
def _set_vect(typingctx, call, address, x, y):  # type: ignore[no-untyped-def]
    """``void f(T *, cpVect)`` at ``call``, with (x, y)."""
    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        target = builder.inttoptr(args[1], _POINTER)
        if _BY_REFERENCE:
            vect = builder.alloca(_VECT)
            builder.store(_VECT(ir.Undefined), vect)
            builder.store(args[2], builder.gep(vect, [ir.Constant(ir.IntType(32), 0),
                                                      ir.Constant(ir.IntType(32), 0)]))
            builder.store(args[3], builder.gep(vect, [ir.Constant(ir.IntType(32), 0),
                                                      ir.Constant(ir.IntType(32), 1)]))
            f = _function(builder, args[0], ir.VoidType(), [_POINTER, _VECT.as_pointer()])
            builder.call(f, [target, vect])
        else:  # a struct of two doubles travels as two doubles
            f = _function(builder, args[0], ir.VoidType(), [_POINTER, _DOUBLE, _DOUBLE])
            builder.call(f, [target, args[2], args[3]])
        return context.get_dummy_value()
    return types.void(types.intp, types.intp, types.float64, types.float64), codegen


if TYPE_CHECKING:  # as compiled code calls them (addresses as integers)
    def get_scalar(call: int, address: int) -> float: ...
    def set_scalar(call: int, address: int, value: float) -> None: ...
    def get_vect(call: int, address: int) -> tuple[float, float]: ...
    def set_vect(call: int, address: int, x: float, y: float) -> None: ...
else:
    get_scalar, set_scalar, get_vect, set_vect = _get_scalar, _set_scalar, _get_vect, _set_vect


@numba.njit(cache=True)
def read_poses(calls: np.ndarray, bodies: np.ndarray, out: np.ndarray) -> None:
    """Each body's (x, y [m], angle [rad]) into ``out`` (n, 3); ``out`` (n, 2): positions."""
    for k in range(bodies.shape[0]):
        out[k, 0], out[k, 1] = get_vect(calls[GET_POSITION], bodies[k])
        if out.shape[1] > 2:
            out[k, 2] = get_scalar(calls[GET_ANGLE], bodies[k])


@numba.njit(cache=True)
def read_motions(calls: np.ndarray, bodies: np.ndarray, out: np.ndarray) -> None:
    """Each body's (angle [rad], vx, vy [m/s], omega [rad/s]) into ``out`` (n, 4)."""
    for k in range(bodies.shape[0]):
        out[k, 0] = get_scalar(calls[GET_ANGLE], bodies[k])
        out[k, 1], out[k, 2] = get_vect(calls[GET_VELOCITY], bodies[k])
        out[k, 3] = get_scalar(calls[GET_SPIN], bodies[k])


@numba.njit(cache=True)
def read_states(calls: np.ndarray, bodies: np.ndarray, out: np.ndarray) -> None:
    """Each body's (x, y [m], vx, vy [m/s], omega [rad/s]) into ``out`` (n, 5)."""
    for k in range(bodies.shape[0]):
        out[k, 0], out[k, 1] = get_vect(calls[GET_POSITION], bodies[k])
        out[k, 2], out[k, 3] = get_vect(calls[GET_VELOCITY], bodies[k])
        out[k, 4] = get_scalar(calls[GET_SPIN], bodies[k])


@numba.njit(cache=True)
def set_velocities(calls: np.ndarray, bodies: np.ndarray, velocities: np.ndarray) -> None:
    """Give each body its row of ``velocities`` (n, 2) [m/s]."""
    for k in range(bodies.shape[0]):
        set_vect(calls[SET_VELOCITY], bodies[k], velocities[k, 0], velocities[k, 1])
