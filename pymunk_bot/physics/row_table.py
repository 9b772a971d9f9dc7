"""Per-robot arrays handed to a compiled pass by address, in one table.

A call from Python into compiled code costs about 60 ns for each array it is given (numba
checks the array's type and wraps it), so a pass over one robot that reads a dozen arrays paid
more to be called than to run. A :class:`RowTable` holds the arrays a pass reads (they live as
long as it does) and gives the pass their addresses and shapes in one integer array; the pass
views each array in place (:func:`floats_1d`, :func:`floats_2d`, :func:`integers_1d`,
:func:`integers_2d`), without a copy. The arrays' order is the pass's contract: it names each
slot, and the table checks every array's type, dimensions and layout when it takes it.

An array is named by its owner and attribute and read from the owner once: per-robot fields
are never rebound after their group is built (copies of a scenario hold theirs in shared arrays
from birth: :mod:`pymunk_bot.robots.rows`), only changed in place.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import numba
import numpy as np
from numba import types
from numba.extending import intrinsic

# A slot of the table: the array's address, its rows and its columns (1 for a 1-D array).
ADDRESS, ROWS, COLUMNS = 0, 1, 2


class RowTable:
    """The arrays of ``fields``, each (owner, attribute, dtype, dimensions) in the order the
    pass reads them, as one table (``table``: each array's address, rows and columns); an
    attribute of None: the owner is the array itself (one the pass's caller made and never
    rebinds)."""

    def __init__(self, fields: Sequence[tuple[Any, str | None, Any, int]]) -> None:
        self.table = np.zeros((len(fields), 3), dtype=np.intp)
        self._arrays: list[np.ndarray] = []  # what the addresses point into, kept alive
        for k, (owner, name, dtype, ndim) in enumerate(fields):
            dtype = np.dtype(dtype)
            array = owner if name is None else getattr(owner, name)
            if not (isinstance(array, np.ndarray) and array.dtype == dtype
                    and array.ndim == ndim and array.flags.c_contiguous):
                what = f"slot {k}" if name is None else f"{type(owner).__name__}.{name}"
                raise TypeError(f"{what} must be a C-contiguous {ndim}-D array of {dtype} for "
                                f"a compiled pass")
            self.table[k] = (array.ctypes.data, array.shape[0],
                             array.shape[1] if ndim == 2 else 1)
            self._arrays.append(array)


@intrinsic
def _as_float_pointer(typingctx, address):  # type: ignore[no-untyped-def]
    """The address (an integer) as a pointer to float64."""
    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))
    return types.CPointer(types.float64)(types.intp), codegen


@intrinsic
def _as_integer_pointer(typingctx, address):  # type: ignore[no-untyped-def]
    """The address (an integer) as a pointer to intp."""
    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))
    return types.CPointer(types.intp)(types.intp), codegen


if TYPE_CHECKING:  # as compiled code calls them
    def _float_pointer(address: int) -> Any: ...
    def _integer_pointer(address: int) -> Any: ...
else:
    _float_pointer, _integer_pointer = _as_float_pointer, _as_integer_pointer


@numba.njit(cache=True)
def floats_1d(table: np.ndarray, k: int) -> np.ndarray:
    """Slot ``k`` of a RowTable's table: a 1-D float64 array, viewed in place."""
    return numba.carray(_float_pointer(table[k, ADDRESS]), table[k, ROWS])


@numba.njit(cache=True)
def floats_2d(table: np.ndarray, k: int) -> np.ndarray:
    """Slot ``k``: a 2-D float64 array, viewed in place."""
    return numba.carray(_float_pointer(table[k, ADDRESS]), (table[k, ROWS], table[k, COLUMNS]))


@numba.njit(cache=True)
def integers_1d(table: np.ndarray, k: int) -> np.ndarray:
    """Slot ``k``: a 1-D intp array, viewed in place."""
    return numba.carray(_integer_pointer(table[k, ADDRESS]), table[k, ROWS])


@numba.njit(cache=True)
def integers_2d(table: np.ndarray, k: int) -> np.ndarray:
    """Slot ``k``: a 2-D intp array, viewed in place."""
    return numba.carray(_integer_pointer(table[k, ADDRESS]),
                        (table[k, ROWS], table[k, COLUMNS]))
