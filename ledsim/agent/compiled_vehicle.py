"""What the vehicle's step derives from its navigation, compiled
(:meth:`~ledsim.agent.autopilot.Vehicle.act_rows` stays the reference and calls this when
:func:`observer.jit.enabled`): the same formulas, one vehicle (row) at a time."""

from __future__ import annotations

import math

import numpy as np

from observer.compiled_math import remainder
from observer.jit import njit


@njit()
def body(gyro, gyro_bias, attitude, delta_velocity, accel_bias, nav_velocity, position,
         l_gimbal, led, bearing0, Te, reaction):
    """Every vehicle's bias-corrected gyro omega [rad/s], mean acceleration a over the
    step [m/s^2], velocity [m/s] and the gimbal hinge's velocity [m/s] (each in the
    hull's frame), and the LED's navigated bearing since the start [rad], as the
    columns of one (N, 13) array: omega 0:3, a 3:6, velocity 6:9, hinge 9:12,
    bearing 12 (``vehicle_frame.hull_frame``)."""
    n = gyro.shape[0]
    out = np.empty((n, 13))
    for r in range(n):
        R = attitude[r]
        for i in range(3):
            out[r, i] = gyro[r, i] - gyro_bias[r, i]
        for i in range(3):
            g = 0.0
            v = 0.0
            for q in range(3):
                g += R[q, i] * reaction[q]
                v += R[q, i] * nav_velocity[r, q]
            out[r, 3 + i] = delta_velocity[r, i] / Te - accel_bias[r, i] - g
            out[r, 6 + i] = v
        w, l = out[r, 0:3], l_gimbal[r]
        out[r, 9] = out[r, 6] + (w[1] * l[2] - w[2] * l[1])
        out[r, 10] = out[r, 7] + (w[2] * l[0] - w[0] * l[2])
        out[r, 11] = out[r, 8] + (w[0] * l[1] - w[1] * l[0])
        heading = math.atan2(R[1, 0], R[0, 0])
        c, s = math.cos(heading), math.sin(heading)
        dx = led[r, 0] - (position[r, 0] + c * l[0] - s * l[1])
        dy = led[r, 1] - (position[r, 1] + s * l[0] + c * l[1])
        out[r, 12] = remainder(math.atan2(dy, dx) - heading, 2 * math.pi) - bearing0[r]
    return out
