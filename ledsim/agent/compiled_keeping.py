"""The station keeping's PD and its load observer's input, compiled
(:class:`~ledsim.agent.keeping.StationKeeper` stays the reference and calls these when
:func:`observer.jit.enabled`): ``_pd_terms``' formulas, one hull (row) at a time."""

from __future__ import annotations

import math

import numpy as np

from observer.compiled_math import remainder, soft_deadband
from observer.jit import njit


@njit()
def measured(omega, prev_omega, k, a, mass, thrust, Te):
    """``M a - thrust`` of every hull (N, 5): the hull-frame acceleration ``a`` (N, 3)
    [m/s^2] on the forces, the gyro's difference over Te on pitch and yaw (0 at a
    hull's first step, ``k`` == 0)."""
    n = omega.shape[0]
    out = np.empty((n, 5))
    for r in range(n):
        for i in range(3):
            out[r, i] = mass[r, i] * a[r, i] - thrust[r, i]
        for i in range(1, 3):
            alpha = (omega[r, i] - prev_omega[r, i]) / Te if k[r] > 0 else 0.0
            out[r, 2 + i] = mass[r, 2 + i] * alpha - thrust[r, 2 + i]
    return out


@njit()
def pd(attitude, position, P, velocity, omega, home_position, home_heading, surface,
       home_velocity, kp, kd, deadband, velocity_deadband):
    """The PD's surge, sway, heave [N], pitch and yaw [N m] of every hull (N, 5), from
    the navigated pose, its covariance (N, 15, 15), the hull-frame velocity [m/s] and
    the bias-corrected gyro [rad/s] (``keeping._pd_terms``)."""
    n = position.shape[0]
    out = np.empty((n, 5))
    err, rate = np.empty(5), np.empty(5)
    two_pi = 2 * math.pi
    for r in range(n):
        heading = math.atan2(attitude[r, 1, 0], attitude[r, 0, 0])
        pitch = math.asin(max(-1.0, min(1.0, -attitude[r, 2, 0])))
        c, s = math.cos(heading), math.sin(heading)
        dx, dy = position[r, 0] - home_position[r, 0], position[r, 1] - home_position[r, 1]
        err[0], err[1] = c * dx + s * dy, -s * dx + c * dy
        err[2] = position[r, 2] - surface[r]
        err[3] = pitch
        err[4] = remainder(heading - home_heading[r], two_pi)
        hvx, hvy = home_velocity[r, 0], home_velocity[r, 1]
        rate[0] = velocity[r, 0] - (c * hvx + s * hvy)
        rate[1] = velocity[r, 1] - (-s * hvx + c * hvy)
        rate[2], rate[3], rate[4] = velocity[r, 2], omega[r, 1], omega[r, 2]
        p = P[r]
        k, kv = deadband, velocity_deadband
        share_xy = soft_deadband(err[0] ** 2 + err[1] ** 2, 0.5 * (p[0, 0] + p[1, 1]), k)
        share_z = soft_deadband(err[2] ** 2, p[2, 2], k)
        share_pitch = soft_deadband(err[3] ** 2, p[7, 7], k)
        share_yaw = soft_deadband(err[4] ** 2, p[8, 8], k)
        vshare_xy = soft_deadband(rate[0] ** 2 + rate[1] ** 2, 0.5 * (p[3, 3] + p[4, 4]), kv)
        vshare_z = soft_deadband(rate[2] ** 2, p[5, 5], kv)
        err[0] *= share_xy
        err[1] *= share_xy
        err[2] *= share_z
        err[3] *= share_pitch
        err[4] *= share_yaw
        rate[0] *= vshare_xy
        rate[1] *= vshare_xy
        rate[2] *= vshare_z
        for i in range(5):
            out[r, i] = -kp[i] * err[i] - kd[i] * rate[i]
    return out
