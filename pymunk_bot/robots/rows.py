"""Where a group keeps its per-robot state: arrays of its own, or rows of arrays every copy of a
scenario shares, from the moment it is built.

A group of robots (the fleet, a drive group, an odometry group and its encoders) names its
per-robot fields (``ROWS``) and takes each from the :class:`Rows` it is built with:
``self.pose = rows.hold("pose", initial)``. A run of its own holds them as they are
(:data:`OWN`). Copies of one scenario sharing a Space (engine/replicas.py) are built on
:class:`SharedRows`: one array per field with every copy's rows, copy 0's first, and each copy's
group holds the view of its rows, its initial values written into them. The group that
bookkeeps every copy at once (robots/stacking.py) holds the whole arrays. Nothing is rebound
after: a copy rebuilt (a reset) writes its new initial values into the same rows, so every
other copy's rows, the whole group and the compiled passes that hold the arrays by address
(physics/row_table.py) keep reading the same memory. A group's methods therefore change these
fields in place.
"""
from __future__ import annotations

import numpy as np


class Rows:
    """Fields held as they are given: a run of its own (:data:`OWN`)."""

    # Whether the fields start from the initial values given (False: they hold a live batch's
    # state, which the group must not take as a fresh start).
    fresh = True

    def hold(self, name: str, initial: np.ndarray) -> np.ndarray:
        """The array the group keeps field ``name`` in, holding ``initial``'s values (a row per
        robot) unless not :attr:`fresh`."""
        return initial

    def within(self, name: str) -> "Rows":
        """Where a part of the group (its encoders: ``"encoders"``) keeps its fields."""
        return self

    # Where each group of a run keeps its fields: the names a build and the stack of copies
    # both use, so the group of every copy at once reads the rows each copy's group holds.
    def of_fleet(self) -> "Rows":
        """The fleet's."""
        return self.within("fleet")

    def of_drive(self, kind: str) -> "Rows":
        """The drive group of drive ``kind``'s."""
        return self.within(f"drive:{kind}")

    def of_odometry(self, kind: str) -> "Rows":
        """The odometry group of drive ``kind``'s."""
        return self.within(f"odometry:{kind}")


OWN = Rows()


class SharedRows:
    """Every field of every group of ``copies`` copies of one scenario, one array each, with a
    row per robot of every copy (each copy's in a block, copy 0's first). Each copy has the
    same robots (copies of one scenario), so each block has the same size."""

    def __init__(self, copies: int) -> None:
        self.copies = copies
        self._arrays: dict[str, np.ndarray] = {}

    def of_copy(self, copy: int) -> Rows:
        """Where copy ``copy``'s groups keep their fields: their block of each array."""
        if not 0 <= copy < self.copies:
            raise IndexError(f"copy {copy} of {self.copies}")
        return _CopyRows(self, copy, "")

    def whole(self) -> Rows:
        """Where the group of every copy at once keeps its fields: the whole arrays, as the
        copies have written them (built after them)."""
        return _WholeRows(self, "")

    def array(self, key: str, initial: np.ndarray) -> np.ndarray:
        """The array of field ``key``, made for ``copies`` blocks shaped like ``initial`` when
        first asked for."""
        array = self._arrays.get(key)
        if array is None:
            shape = (self.copies * initial.shape[0],) + initial.shape[1:]
            array = self._arrays[key] = np.zeros(shape, dtype=initial.dtype)
        elif (array.shape[0] != self.copies * initial.shape[0]
              or array.shape[1:] != initial.shape[1:] or array.dtype != initial.dtype):
            raise ValueError(f"copies of one scenario hold '{key}' alike: "
                             f"{initial.dtype}{list(initial.shape)} per copy, "
                             f"not {array.dtype}{list(array.shape)} for {self.copies}")
        return array

    def held(self, key: str) -> np.ndarray:
        """The array of field ``key``, which some copy has held."""
        if key not in self._arrays:
            raise KeyError(f"no copy holds '{key}'")
        return self._arrays[key]


class _CopyRows(Rows):
    """One copy's block of a :class:`SharedRows`' arrays."""

    def __init__(self, shared: SharedRows, copy: int, prefix: str) -> None:
        self._shared, self._copy, self._prefix = shared, copy, prefix

    def hold(self, name: str, initial: np.ndarray) -> np.ndarray:
        initial = np.ascontiguousarray(initial)
        n = initial.shape[0]
        block = self._shared.array(self._prefix + name, initial)[self._copy * n:
                                                                 (self._copy + 1) * n]
        block[...] = initial
        return block

    def within(self, name: str) -> Rows:
        return _CopyRows(self._shared, self._copy, f"{self._prefix}{name}.")


class _WholeRows(Rows):
    """Every copy's rows of a :class:`SharedRows`' arrays, as they are."""

    fresh = False

    def __init__(self, shared: SharedRows, prefix: str) -> None:
        self._shared, self._prefix = shared, prefix

    def hold(self, name: str, initial: np.ndarray) -> np.ndarray:
        array = self._shared.held(self._prefix + name)
        if array.shape != initial.shape:
            raise ValueError(f"the whole of '{self._prefix}{name}' is {list(array.shape)}, "
                             f"not {list(initial.shape)}")
        return array

    def within(self, name: str) -> Rows:
        return _WholeRows(self._shared, f"{self._prefix}{name}.")
