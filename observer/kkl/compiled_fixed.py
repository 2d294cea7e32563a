"""The fixed-gain KKL's update and predict (:class:`~observer.kkl.fixed_gain.KKLObserver`),
compiled: one call each a step, for a system that gives its f as numbers
(``compiled_f``: the angle's and the rate's coefficients, as the identified gimbal model
and one axis of a pan-tilt head give them) and maps of one hidden layer.

The reference makes a dozen numpy calls a step (the decoder, and with an input the
encoder twice and f twice), each of which allocates; here each map is one loop nest
(:mod:`observer.kkl.compiled_maps`' hidden layer and its tanh) and f is plain arithmetic
in the reference's order.
"""

from __future__ import annotations

import numpy as np

from observer.compiled_math import axis_f
from observer.jit import njit
from observer.kkl.compiled_maps import _hidden
from observer.kkl.compiled_step import checks


@njit(fastmath={"contract", "reassoc"})
def mlp(v: np.ndarray, W1T: np.ndarray, b1: np.ndarray, W2: np.ndarray,
        b2: np.ndarray, h: np.ndarray, bits: np.ndarray, out: np.ndarray) -> None:
    """``out = W2 tanh(W1 v + b1) + b2`` for one sample ``v`` (n_in,), as
    :meth:`~observer.kkl.nets.NumpyMLP.vector` (``W1T`` (n_in, H), ``W2`` (n_out, H),
    both C-contiguous); ``h`` and ``bits`` are scratch of H floats and int64s."""
    _hidden(v, W1T, b1, h, bits)
    for o in range(out.size):  # along W2's rows: contiguous, so the sum vectorises
        acc = 0.0
        for k in range(h.size):
            acc += h[k] * W2[o, k]
        out[o] = acc + b2[o]


@njit()
def _inside(x: np.ndarray, low: np.ndarray, high: np.ndarray) -> bool:
    for i in range(x.size):
        if not low[i] <= x[i] <= high[i]:
            return False
    return True


@njit()
def update(z: np.ndarray, y: np.ndarray, W1T: np.ndarray, b1: np.ndarray,
           W2: np.ndarray, b2: np.ndarray, low: np.ndarray, high: np.ndarray,
           y_low: np.ndarray, y_high: np.ndarray, bounded: bool):
    """(x_hat = T*(z), x_hat in the box [low, high], every output usable): the
    reference's update but for the missing outputs, which the caller replaces by h(x_hat)
    where the last is False (``y_low``/``y_high`` the outputs' bounds where ``bounded``)."""
    H = b1.size
    xhat = np.empty(b2.size)
    mlp(z, W1T, b1, W2, b2, np.empty(H), np.empty(H, np.int64), xhat)
    inside, usable = checks(xhat, low, high, y, y_low, y_high, bounded)
    return xhat, inside, usable


@njit()
def predict(z: np.ndarray, y: np.ndarray, estimate: np.ndarray, u: float, u_bar: float,
            use_omega: bool, lam: np.ndarray, B: np.ndarray, a: np.ndarray,
            b: np.ndarray, W1T: np.ndarray, b1: np.ndarray, W2: np.ndarray,
            b2: np.ndarray, low: np.ndarray, high: np.ndarray):
    """(z' = A z + B y + Omega(z, u), f(x_hat, u) in the box): the reference's predict
    with a scalar input, at the decoded ``estimate`` (the axis's angle [rad] and rate
    [rad/s]); the encoder's weights ``W1T``.. (Omega only where u != u_bar)."""
    q = z.size
    z_next = np.empty(q)
    for i in range(q):
        acc = 0.0
        for j in range(y.size):
            acc += B[i, j] * y[j]
        z_next[i] = lam[i] * z[i] + acc
    inside = True
    if use_omega and u != u_bar:
        H = b1.size
        h, bits = np.empty(H), np.empty(H, np.int64)
        angle, rate = estimate[0], estimate[1]  # the axis's two states
        driven = np.array(axis_f(angle, rate, u, a, b))
        rest = np.array(axis_f(angle, rate, u_bar, a, b))
        inside = _inside(driven, low, high)
        e_driven, e_rest = np.empty(q), np.empty(q)
        mlp(driven, W1T, b1, W2, b2, h, bits, e_driven)
        mlp(rest, W1T, b1, W2, b2, h, bits, e_rest)
        for i in range(q):
            z_next[i] = (z_next[i] + e_driven[i]) - e_rest[i]
    return z_next, inside
