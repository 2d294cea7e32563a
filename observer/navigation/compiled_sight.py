"""The line of sight filter's step, compiled (:meth:`~observer.navigation.line_of_sight.
LineOfSightFilter.update_rows` stays the reference and calls it when
:func:`observer.jit.enabled`): ``line_of_sight._step``'s formulas, one vehicle (row) at
a time."""

from __future__ import annotations

import math

import numpy as np

from observer.compiled_math import remainder
from observer.jit import njit


@njit()
def step(raw, power, rate, bearing, anchor, k, v_gimbal, encoder, hull_rate, nav_bearing,
         noise_power, ranges, constants):
    """Every vehicle's new (raw, power, rate, bearing, anchor, acceleration, hull rate),
    as the rows of one (7, N) array. ``noise_power`` (N,): the rate's noise power at
    each range; ``constants``: (k_rate, k_power, Te, reanchor_rate, reanchor_time,
    k_reanchor, k_bearing)."""
    k_rate, k_power, Te, reanchor_rate, reanchor_time, k_reanchor, k_bearing = \
        constants[0], constants[1], constants[2], constants[3], constants[4], \
        constants[5], constants[6]
    n = raw.shape[0]
    out = np.empty((7, n))
    two_pi = 2 * math.pi
    for r in range(n):
        c, s = math.cos(encoder[r]), math.sin(encoder[r])
        w = (-c * v_gimbal[r, 1] + s * v_gimbal[r, 0]) / ranges[r]
        new_raw = raw[r] + k_rate * (w - raw[r])
        new_power = power[r] + k_power * (new_raw**2 - power[r])
        new_rate = new_raw * max(0.0, 1.0 - noise_power[r] / max(new_power, 1e-30))
        accel = (new_rate - rate[r]) / Te if k[r] > 0 else 0.0
        b = bearing[r] + Te * (new_rate - hull_rate[r])
        a = reanchor_time if abs(w) > reanchor_rate else anchor[r]
        pulled = a > 0
        gain = k_reanchor if pulled else k_bearing
        if pulled:
            a = a - Te
        b = b + gain * remainder(nav_bearing[r] - b, two_pi)
        out[0, r], out[1, r], out[2, r], out[3, r] = new_raw, new_power, new_rate, b
        out[4, r], out[5, r], out[6, r] = a, accel, hull_rate[r] * 1.0
    return out
