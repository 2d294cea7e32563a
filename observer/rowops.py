"""The arithmetic of a row kernel, for one row in plain floats or for N rows in arrays.

A kernel written once against ``o`` (:data:`FLOATS` or :data:`ARRAYS`) computes one
row's numbers (a vehicle's, a sensor's) in Python floats, where numpy's per-call cost
would be most of the work, or every row's at once, with the same operations element
by element: IEEE arithmetic, and libm's functions on both sides (numpy's own
``arctan2``, ``arcsin``, ``arccos``, ``exp`` and ``x ** 2`` differ from libm's in the
last bit, so the arrays call libm per element there; its ``sqrt``, ``cos`` and ``sin``
do not). ``tests/test_vehicle_rows.py`` and ``tests/test_sensor_rows.py`` hold the two
to the same bits.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from observer.navigation.rotations import libm_square, per_element

#: Plain floats (one row).
FLOATS = SimpleNamespace(
    cos=math.cos, sin=math.sin, atan2=math.atan2, asin=math.asin, acos=math.acos,
    exp=math.exp, sqrt=math.sqrt, remainder=math.remainder, square=lambda x: x**2,
    pow=lambda x, y: x**y, abs=abs, maximum=max, minimum=min,
    where=lambda c, a, b: a if c else b)

#: Arrays of N rows.
ARRAYS = SimpleNamespace(
    cos=np.cos, sin=np.sin, atan2=lambda y, x: per_element(math.atan2, y, x),
    asin=lambda x: per_element(math.asin, x), acos=lambda x: per_element(math.acos, x),
    exp=lambda x: per_element(math.exp, x), sqrt=np.sqrt,  # IEEE's sqrt: one rounding
    remainder=lambda x, y: per_element(math.remainder, x, y), square=libm_square,
    pow=lambda x, y: per_element(math.pow, x, y), abs=np.abs, maximum=np.maximum,
    minimum=np.minimum, where=np.where)


def ops(n: int) -> SimpleNamespace:
    """The arithmetic for ``n`` rows."""
    return FLOATS if n == 1 else ARRAYS


def columns(n: int, *arrays):
    """Each of ``arrays`` ((n,) or (n, k) sliced by the caller) as a float for one row,
    unchanged for several."""
    return tuple(float(a[0]) for a in arrays) if n == 1 else arrays
