"""The EKF's update and predict on a one-axis gimbal model, compiled
(:class:`~observer.baselines.ekf.ExtendedKalmanFilter` stays the reference and calls
these when :func:`observer.jit.enabled` and its system gives f and h as numbers:
``compiled_f`` and ``compiled_h``, as ``IdentifiedGimbalModel`` does, with a noise that
does not depend on the signal). The same formulas: h = gain x g(phi + offset_i) with
the two-Gaussian g, f with linear and quadratic drag, R over the usable outputs (with
the model's relative error and the told noise scale), the divergence count, and the
Joseph form; the 2x2 products sum in loop order where numpy's BLAS sums in its own."""

from __future__ import annotations

import math

import numpy as np

from observer.compiled_math import axis_f, matmul
from observer.jit import njit
from observer.supervision.compiled_pair import response_and_slope


@njit()
def update(mean, P, y, y_lo, y_hi, bounded, gain, offsets, response, R_model, model_error,
           noise_scale, lost_nis, lost_steps, inconsistent):
    """One measurement ``y`` [W] at the estimate ``mean`` (phi [rad], phidot [rad/s]) and
    its covariance P: returns (mean, P, the count of implausible innovations in a row,
    diverged). ``diverged``: the count reached ``lost_steps`` (the caller starts the
    filter again); mean and P are then the ones given."""
    phi = mean[0]  # the rate does not enter h
    m = y.size
    ok = np.empty(m, dtype=np.bool_)
    k = 0
    for i in range(m):
        ok[i] = math.isfinite(y[i]) and (not bounded or (y_lo[i] <= y[i] <= y_hi[i]))
        if ok[i]:
            k += 1
    if k == 0:
        return mean.copy(), P.copy(), inconsistent, False
    H = np.zeros((k, 2))
    innov, R = np.empty(k), np.zeros((k, k))
    j = 0
    for i in range(m):
        if not ok[i]:
            continue
        g, slope = response_and_slope(phi + offsets[i], response[0], response[1],
                                      response[2], response[3], response[4], response[5])
        H[j, 0] = gain * slope
        y_pred = gain * g
        innov[j] = y[i] - y_pred
        r = R_model[i, i]
        if model_error != 0.0:
            r = r + (model_error * y_pred) ** 2
        if noise_scale != 1.0:
            r = r * (noise_scale * noise_scale)
        R[j, j] = r
        j += 1
    HP = matmul(H, P)
    S = matmul(HP, H, True) + R
    Sinv = _inverse(S)
    nis = 0.0
    for a in range(k):
        for b in range(k):
            nis += innov[a] * Sinv[a, b] * innov[b]
    inconsistent = inconsistent + 1 if nis > lost_nis * k else 0
    if inconsistent >= lost_steps:
        return mean.copy(), P.copy(), inconsistent, True
    K = matmul(Sinv, HP).T.copy()
    out = mean.copy()
    for a in range(2):
        for b in range(k):
            out[a] += K[a, b] * innov[b]
    IKH = np.eye(2) - matmul(K, H)
    P_new = matmul(matmul(IKH, P), IKH, True) + matmul(matmul(K, R), K, True)
    return out, P_new, inconsistent, False


@njit()
def _inverse(S):
    """S^-1 of a small matrix: Gauss-Jordan with partial pivoting (numba's own inverse
    needs scipy's LAPACK)."""
    n = S.shape[0]
    A, out = S.copy(), np.eye(n)
    for c in range(n):
        p = c
        for r in range(c + 1, n):
            if abs(A[r, c]) > abs(A[p, c]):
                p = r
        if p != c:
            for j in range(n):
                A[c, j], A[p, j] = A[p, j], A[c, j]
                out[c, j], out[p, j] = out[p, j], out[c, j]
        d = A[c, c]
        for j in range(n):
            A[c, j] /= d
            out[c, j] /= d
        for r in range(n):
            if r != c:
                f = A[r, c]
                for j in range(n):
                    A[r, j] -= f * A[c, j]
                    out[r, j] -= f * out[c, j]
    return out


@njit()
def predict(mean, P, u, coef_phi, coef_rate, Q, box):
    """One step of the estimate ``mean`` (phi [rad], phidot [rad/s]) and P under input
    ``u`` [rad/s^2]: returns (mean, P, contained); ``contained`` False when the mean left
    ``box`` ((2, 2): each state's bounds) or P is not finite (the caller starts the
    filter again)."""
    d_drag = 2 * abs(mean[1])
    F = np.array([[1.0, coef_phi[0] + coef_phi[2] * d_drag],
                  [0.0, coef_rate[0] + coef_rate[2] * d_drag]])
    out = np.array(axis_f(mean[0], mean[1], u, coef_phi, coef_rate))
    P_new = matmul(matmul(F, P), F, True) + Q
    contained = math.isfinite(P_new.sum())
    for i in range(2):
        if not (box[i, 0] <= out[i] <= box[i, 1]):
            contained = False
    return out, P_new, contained
