"""One object for the same estimator of many vehicles or worlds: :class:`Rows`.

A class that keeps each instance's state in arrays with a leading axis of N (one row
each) and in lists of N per-row objects (generators, queues) can stack several of its
single instances into one (:meth:`Rows.stacked`), and put a single instance back into a
row (:meth:`Rows.put`: a world that restarted). Its methods then compute every row as
the single instance would, so a row's numbers do not depend on the others.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence

import numpy as np


def transposed(a: np.ndarray) -> np.ndarray:
    """The transpose of each matrix of a stack (..., m, k) -> (..., k, m)."""
    return a.swapaxes(-1, -2)


def matvec(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """A @ x of each row: (N, m, k) or (m, k) by (N, k) -> (N, m), through the BLAS
    call one matrix by one vector takes (the same bits as one row alone)."""
    return (A @ x[..., None])[..., 0]


class Rows:
    """Mixin: the names of the per-row arrays (``ROW_ARRAYS``) and lists
    (``ROW_LISTS``) of a class with ``n`` rows and a ``single`` flag (one instance as
    one row: its public surface drops the row axis)."""

    ROW_ARRAYS: tuple[str, ...] = ()
    ROW_LISTS: tuple[str, ...] = ()

    @classmethod
    def stacked(cls, items: Sequence[Rows]):
        """One instance with the rows of ``items`` (instances of this class, each of any
        number of rows), in order; their shared settings (every other array or number)
        must be equal (else ``ValueError``: a row would not get its own)."""
        rows = set(cls.ROW_ARRAYS) | set(cls.ROW_LISTS)
        for name, value in vars(items[0]).items():
            if name in rows or not isinstance(value, np.ndarray | float | int):
                continue
            for other in items[1:]:
                if not _same(value, getattr(other, name)):
                    raise ValueError(f"{cls.__name__}.{name} differs between the items: "
                                     "it cannot be shared by their rows")
        out = copy.copy(items[0])
        for name in cls.ROW_ARRAYS:
            setattr(out, name, np.concatenate([getattr(i, name) for i in items]))
        for name in cls.ROW_LISTS:
            setattr(out, name, [x for i in items for x in getattr(i, name)])
        out.n = sum(i.n for i in items)
        out.single = False
        return out

    def put(self, row: int, item: Rows) -> None:
        """Row ``row`` becomes the (one-row) ``item``'s state."""
        for name in self.ROW_ARRAYS:
            mine = getattr(self, name).copy()  # a new array: earlier reads stay as they were
            mine[row] = getattr(item, name)[0]
            setattr(self, name, mine)
        for name in self.ROW_LISTS:
            getattr(self, name)[row] = getattr(item, name)[0]


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.shape == b.shape and \
            bool(np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    return a == b or (a != a and b != b)
