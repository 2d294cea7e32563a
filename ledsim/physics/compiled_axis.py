"""One pan-tilt axis's fix from the head's powers (:meth:`~ledsim.physics.axis_model.
AxisRatioModel.fix`), compiled, to the reference's last bit: the same divisions, libm's
``log`` and ``exp``, Python's ``bisect_right`` on the same grid and the sum in the same
order. NaN stands for the reference's None."""

from __future__ import annotations

import math

import numpy as np

from observer.jit import njit
from observer.supervision.compiled_pair import response_and_slope


@njit()
def _bisect_right(v: np.ndarray, x: float) -> int:
    """``bisect.bisect_right(v, x)`` on the increasing ``v``."""
    lo, hi = 0, v.size
    while lo < hi:
        mid = (lo + hi) // 2
        if x < v[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo


@njit()
def fix(y: np.ndarray, gains: np.ndarray, i: int, j: int, ref: int, v: np.ndarray,
        angle: np.ndarray, turns: np.ndarray, r: np.ndarray, tolerance: float) -> float:
    """The axis's angle [rad] from the powers ``y`` [W] (NaN: none), as the reference:
    the pair (i, j) over the detector ``ref``, each over its channel's gain, inverted on
    the grid (``v``: the log ratio difference, increasing; ``angle`` [rad]) and checked
    against the receiver's product (``turns`` [rad]; ``r``: its a1, b1, c1, a2, b2, c2)."""
    p0, pi, pj = y[ref] / gains[ref], y[i] / gains[i], y[j] / gains[j]
    if not (p0 > 0 and pi > 0 and pj > 0 and math.isfinite(p0) and math.isfinite(pi)
            and math.isfinite(pj)):
        return np.nan
    log_plus, log_minus = math.log(pi / p0), math.log(pj / p0)
    value = log_plus - log_minus
    n = v.size
    if not v[0] <= value <= v[n - 1]:
        return np.nan
    k = min(max(_bisect_right(v, value), 1), n - 1)
    out = angle[k - 1] + (angle[k] - angle[k - 1]) * (value - v[k - 1]) / (v[k] - v[k - 1])
    g0 = response_and_slope(out, r[0], r[1], r[2], r[3], r[4], r[5])[0]
    expected = 0.0  # sum()'s start
    for d in turns:
        g = response_and_slope(out + d, r[0], r[1], r[2], r[3], r[4], r[5])[0]
        expected += math.log(g / g0)
    if abs(log_plus + log_minus - expected) > tolerance:
        return np.nan
    return out
