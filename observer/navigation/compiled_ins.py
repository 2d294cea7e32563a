"""The aided INS's propagation and depth update, compiled (:class:`~observer.navigation.ins.
AidedINS` stays the reference and calls these when :func:`observer.jit.enabled`).

The same formulas as the reference, row by row: Rodrigues' exponential as
``rotations._exp_one`` writes it, the attitude, velocity and position, the error's
transition F (first order in Te) and P' = F P F^T + Q. Each row is computed by the same
loops whatever the number of rows, so a vehicle's navigation does not depend on the
batch it runs in; the products sum in loop order where the reference's BLAS sums in its
own, so the two part in the last bits (``tests/test_compiled_vehicle.py``).
"""

from __future__ import annotations

import math

import numpy as np

from observer.compiled_math import matmul
from observer.jit import njit

#: First index of each error-state block: position, velocity, attitude, the biases.
_P, _V, _TH, _BG, _BA = 0, 3, 6, 9, 12


@njit()
def rotation_exp(rotvec: np.ndarray) -> np.ndarray:
    """Exp (3, 3) of one rotation vector [rad], as ``rotations._exp_one``."""
    x, y, z = rotvec[0], rotvec[1], rotvec[2]
    angle = math.sqrt(x**2 + y**2 + z**2)
    K = np.array([[x * 0.0, z * -1.0, y], [z, x * 0.0, x * -1.0], [y * -1.0, x, x * 0.0]])
    K2 = matmul(K, K)
    out = np.empty((3, 3))
    if angle < 1e-9:
        a, b = 1.0, 0.5
    else:
        a, b = math.sin(angle) / angle, (1.0 - math.cos(angle)) / angle**2
    for i in range(3):
        for j in range(3):
            out[i, j] = (1.0 if i == j else 0.0) + a * K[i, j] + b * K2[i, j]
    return out


@njit()
def propagate(position, velocity, attitude, gyro_bias, accel_bias, Ps, F, Q,
              delta_angle, delta_velocity, Te, gravity, displacements):
    """One IMU period of every row (``AidedINS.propagate_rows``): returns the new
    (position, velocity, attitude, P, displacement) arrays; ``F`` (N, 15, 15) is
    updated in place (its constant blocks stay as built)."""
    n = position.shape[0]
    pos, vel, att = np.empty_like(position), np.empty_like(velocity), np.empty_like(attitude)
    P_new, disp = np.empty_like(Ps), np.empty_like(displacements)
    dth, dv = np.empty(3), np.empty(3)
    for r in range(n):
        for i in range(3):
            dth[i] = delta_angle[r, i] - gyro_bias[r, i] * Te
            dv[i] = delta_velocity[r, i] - accel_bias[r, i] * Te
        turn = rotation_exp(dth)
        R = matmul(attitude[r], turn)
        for i in range(3):
            s = 0.0
            for j in range(3):
                s += R[i, j] * dv[j]
            vel[r, i] = velocity[r, i] + s
        vel[r, 2] -= Te * gravity
        for i in range(3):
            step = 0.5 * Te * (velocity[r, i] + vel[r, i])
            pos[r, i] = position[r, i] + step
            disp[r, i] = displacements[r, i] + step
        att[r] = R
        # R [dv]x, as R @ skew(dv)
        S = np.array([[dv[0] * 0.0, dv[2] * -1.0, dv[1]], [dv[2], dv[0] * 0.0, dv[0] * -1.0],
                      [dv[1] * -1.0, dv[0], dv[0] * 0.0]])
        Rdv = matmul(R, S)
        f = F[r]
        for i in range(3):
            for j in range(3):
                s = 0.0
                for q in range(3):
                    s += Rdv[i, q] * turn[j, q]
                f[_V + i, _TH + j] = -s
                f[_V + i, _BG + j] = Rdv[i, j] * Te
                f[_V + i, _BA + j] = -R[i, j] * Te
                f[_TH + i, _TH + j] = turn[j, i]
        for i in range(3):
            for j in range(3):
                f[_P + i, _TH + j] = 0.5 * Te * f[_V + i, _TH + j]
                f[_P + i, _BG + j] = 0.5 * Te * f[_V + i, _BG + j]
                f[_P + i, _BA + j] = 0.5 * Te * f[_V + i, _BA + j]
        # F P F^T + Q
        FPF = matmul(matmul(f, Ps[r]), f, True)
        for i in range(15):
            for j in range(15):
                P_new[r, i, j] = FPF[i, j] + Q[i, j]
    return pos, vel, att, P_new, disp


@njit()
def depth_update(position, velocity, attitude, gyro_bias, accel_bias, Ps, depth,
                 surface, depth_var):
    """A depth reading [m] of every row (``InsAiding.depth_rows``): P updated in place;
    returns the corrected (position, velocity, attitude, gyro bias, accel bias)."""
    n = position.shape[0]
    pos, vel, att = position.copy(), velocity.copy(), np.empty_like(attitude)
    bg, ba = gyro_bias.copy(), accel_bias.copy()
    ph, dx = np.empty(15), np.empty(3)
    for r in range(n):
        p = Ps[r]
        res = depth[r] - (surface[r] - position[r, 2])
        for i in range(15):
            ph[i] = p[i, 2]
        S = ph[2] + depth_var
        for i in range(15):
            for j in range(15):
                p[i, j] -= ph[i] * ph[j] / S
        gain = -res / S
        for i in range(3):
            pos[r, i] += ph[_P + i] * gain
            vel[r, i] += ph[_V + i] * gain
            dx[i] = ph[_TH + i] * gain
            bg[r, i] += ph[_BG + i] * gain
            ba[r, i] += ph[_BA + i] * gain
        att[r] = matmul(attitude[r], rotation_exp(dx))
    return pos, vel, att, bg, ba
