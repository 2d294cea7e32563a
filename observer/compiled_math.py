"""Scalar helpers the compiled kernels share (numba lacks ``math.remainder``)."""

from __future__ import annotations

import numpy as np

from observer.jit import njit


@njit()
def remainder(x: float, y: float) -> float:
    """``math.remainder(x, y)`` for y > 0: x less the nearest multiple of y, in
    [-y/2, y/2]. fmod is exact, and so is the one subtraction of y (Sterbenz); only a
    tie, exactly y/2 off, may round the other way."""
    r = np.fmod(x, y)
    if r > 0.5 * y:
        return r - y
    if r < -0.5 * y:
        return r + y
    return r


@njit()
def soft_deadband(square: float, variance: float, k: float) -> float:
    """``observer.navigation.hull_loads.soft_deadband`` of one quantity."""
    if k == 0.0:
        return 1.0
    ratio = k * k * variance / max(square, 1e-300)
    return 0.0 if ratio >= 1.0 else 1.0 - ratio * ratio


@njit()
def matmul(A: np.ndarray, B: np.ndarray, b_transposed: bool = False) -> np.ndarray:
    """A @ B (A @ B^T with ``b_transposed``) of two small matrices, summed in loop
    order."""
    n, q = A.shape[0], A.shape[1]
    m = B.shape[0] if b_transposed else B.shape[1]
    out = np.zeros((n, m))
    for i in range(n):
        for j in range(m):
            s = 0.0
            for t in range(q):
                s += A[i, t] * (B[j, t] if b_transposed else B[t, j])
            out[i, j] = s
    return out


@njit()
def axis_f(angle: float, rate: float, u: float, a: np.ndarray, b: np.ndarray
           ) -> tuple[float, float]:
    """One step of an identified axis (angle [rad], rate [rad/s]) under input ``u``:
    (angle + a1 rate + a2 u + a3 |rate| rate, b1 rate + b2 u + b3 |rate| rate), in the
    order of the reference's plain-float path (``IdentifiedGimbalModel.f``)."""
    drag = abs(rate) * rate
    return angle + (a[0] * rate + a[1] * u + a[2] * drag), b[0] * rate + b[1] * u + b[2] * drag
