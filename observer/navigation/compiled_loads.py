"""The hull's disturbance observer's step, compiled (:meth:`~observer.navigation.
hull_loads.HullLoadObserver.update_rows` stays the reference and calls it when
:func:`observer.jit.enabled`): the same formulas, one row and one axis at a time."""

from __future__ import annotations

import numpy as np

from observer.compiled_math import soft_deadband
from observer.jit import njit


@njit()
def update(load, slow_load, measured, limit, k_fast, k_slow, slow_variance,
           gust_variance, deadband):
    """One period of every row (N, 5): returns the new (fast load, slow load, the load
    to cancel). ``limit`` (5,): the slow estimate's clip (inf: none)."""
    n, m = load.shape
    fast, slow, out = np.empty_like(load), np.empty_like(load), np.empty_like(load)
    for r in range(n):
        for i in range(m):
            f = load[r, i] + k_fast * (measured[r, i] - load[r, i])
            x = min(max(measured[r, i], -limit[i]), limit[i])
            s = slow_load[r, i] + k_slow * (x - slow_load[r, i])
            g = f - s
            fast[r, i], slow[r, i] = f, s
            out[r, i] = s * soft_deadband(s * s, slow_variance[r, i], deadband) \
                + g * soft_deadband(g * g, gust_variance[r, i], deadband)
    return fast, slow, out
