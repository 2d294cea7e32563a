"""The KKL's maps on a few samples, compiled: one call per map and step.

A map of :class:`~observer.kkl.gainmaps.GainTableMap` on one sample is small arithmetic
(a 10 x 750 or 2 x 1000 hidden layer, a few outputs) spread over a dozen numpy calls,
each of which allocates; here the hidden layer, its tanh and the output layer run in one
loop nest with no allocation but the layer's scratch.

The tanh is Cephes' (a rational function near 0, ``1 - 2 / (exp(2|x|) + 1)`` beyond 0.625,
exp by Cody-Waite reduction and a rational function): written in plain arithmetic so
that LLVM vectorises it, it runs at numpy's SIMD speed where a loop of ``math.tanh``
(libm, one value at a time) is 4-5x slower. It is within 2 ulp of ``np.tanh`` (itself 2
ulp from libm), tested over the whole line.
"""

from __future__ import annotations

import math

import numpy as np

from observer.jit import njit

# Cephes tanh, |x| < 0.625: x + x z P(z) / Q(z), z = x^2 (Q monic).
_TP0, _TP1, _TP2 = -9.64399179425052238628e-1, -9.92877231001918586564e1, \
    -1.61468768441708447952e3
_TQ0, _TQ1, _TQ2 = 1.12811678491632931402e2, 2.23548839060100448583e3, \
    4.84406305325125486048e3
# Cephes exp on [-ln2 / 2, ln2 / 2]: 1 + 2 r P(r^2) / (Q(r^2) - r P(r^2)).
_EP0, _EP1, _EP2 = 1.26177193074810590878e-4, 3.02994407707441961300e-2, \
    9.99999999999999999910e-1
_EQ0, _EQ1, _EQ2, _EQ3 = 3.00198505138664455042e-6, 2.52448340349684104192e-3, \
    2.27265548208155028766e-1, 2.00000000000000000009e0
_LN2_HI, _LN2_LO = 6.93145751953125e-1, 1.42860682030941723212e-6
_LOG2E = 1.4426950408889634073599
#: 2|x| beyond which tanh(x) rounds to +-1 in float64 (tanh(19.1) = 1 - 5e-17).
_SATURATED = 40.0


@njit(fastmath={"contract"})
def tanh_inplace(h: np.ndarray, bits: np.ndarray) -> None:
    """``h = tanh(h)`` in place (float64, 1-D); ``bits`` is int64 scratch of h's size.
    NaN stays NaN."""
    n = h.size
    for i in range(n):  # 2^k of each exp(2|x|) = 2^k e^r, as the bits of a float64
        k = math.floor(_LOG2E * min(2.0 * abs(h[i]), _SATURATED) + 0.5)
        bits[i] = (np.int64(k) + 1023) << 52
    scale = bits.view(np.float64)
    for i in range(n):
        x = h[i]
        ax = abs(x)
        z = x * x
        small = ax + ax * z * (((_TP0 * z + _TP1) * z + _TP2)
                               / (((z + _TQ0) * z + _TQ1) * z + _TQ2))
        y = min(2.0 * ax, _SATURATED)
        k = math.floor(_LOG2E * y + 0.5)
        r = y - k * _LN2_HI - k * _LN2_LO
        rr = r * r
        p = r * ((_EP0 * rr + _EP1) * rr + _EP2)
        e = (1.0 + 2.0 * (p / ((((_EQ0 * rr + _EQ1) * rr + _EQ2) * rr + _EQ3) - p))) * scale[i]
        big = 1.0 - 2.0 / (e + 1.0)
        h[i] = math.copysign(small if ax < 0.625 else big, x)  # odd: exactly, and -0 too


@njit(fastmath={"contract"})
def _hidden(v: np.ndarray, W1T: np.ndarray, b1: np.ndarray, h: np.ndarray,
            bits: np.ndarray) -> None:
    """h = tanh(v W1T + b1) for one sample ``v`` (n_in,), ``W1T`` (n_in, H)."""
    H = h.size
    for j in range(H):
        h[j] = 0.0
    for k in range(v.size):  # over the hidden units inside: vectorises as it stands
        vk = v[k]
        for j in range(H):
            h[j] += vk * W1T[k, j]
    for j in range(H):
        h[j] += b1[j]
    tanh_inplace(h, bits)


@njit(fastmath={"contract", "reassoc"})
def _output(coef: np.ndarray, i: int, i1: int, a: float, j: int, j1: int, b: float,
            h: np.ndarray, weight: float, out: np.ndarray) -> None:
    """out += weight (C[:, :H] h + C[:, H]) with the output weights C interpolated as
    :class:`~observer.kkl.gainmaps.GainTableMap` does: in the noise, (1 - b) at grid
    noise j and b at j1, and (for a shared hidden layer, ``a > 0``) in the gain, (1 - a)
    at grid gain i and a at i1; ``coef`` (n_w, n_s, n_out, H + 1)."""
    H = h.size
    for o in range(coef.shape[2]):
        acc = 0.0
        if a > 0:
            for k in range(H):
                lo = (1 - b) * coef[i, j, o, k] + b * coef[i, j1, o, k]
                hi = (1 - b) * coef[i1, j, o, k] + b * coef[i1, j1, o, k]
                acc += ((1 - a) * lo + a * hi) * h[k]
            lo = (1 - b) * coef[i, j, o, H] + b * coef[i, j1, o, H]
            hi = (1 - b) * coef[i1, j, o, H] + b * coef[i1, j1, o, H]
            out[o] += weight * (acc + ((1 - a) * lo + a * hi))
        else:
            for k in range(H):
                acc += ((1 - b) * coef[i, j, o, k] + b * coef[i, j1, o, k]) * h[k]
            out[o] += weight * (acc + ((1 - b) * coef[i, j, o, H] + b * coef[i, j1, o, H]))


@njit()
def map_rows(v: np.ndarray, W1T: np.ndarray, b1: np.ndarray, coef: np.ndarray, i: int,
             i1: int, a: float, j: int, j1: int, b: float, shared: bool,
             out: np.ndarray) -> None:
    """:class:`~observer.kkl.gainmaps.GainTableMap` at grid brackets (i, i1, a) of the
    gain and (j, j1, b) of the noise, on each row of ``v`` (N, n_in), into ``out`` (N,
    n_out). ``W1T`` (n_w or 1, n_in, H) and ``b1`` (n_w or 1, H) are the hidden layers:
    one shared (its output weights interpolated in the gain), or one per grid gain (the
    two maps' outputs interpolated, the second not evaluated at ``a == 0``)."""
    H = b1.shape[1]
    h = np.empty(H)
    bits = np.empty(H, np.int64)
    for r in range(v.shape[0]):
        for o in range(out.shape[1]):
            out[r, o] = 0.0
        if shared:
            _hidden(v[r], W1T[0], b1[0], h, bits)
            _output(coef, i, i1, a, j, j1, b, h, 1.0, out[r])
            continue
        _hidden(v[r], W1T[i], b1[i], h, bits)
        _output(coef, i, i, 0.0, j, j1, b, h, 1.0 - a, out[r])
        if a > 0:
            _hidden(v[r], W1T[i1], b1[i1], h, bits)
            _output(coef, i1, i1, 0.0, j, j1, b, h, a, out[r])


@njit()
def interpolated_weights(coef: np.ndarray, i: int, i1: int, a: float, j: int, j1: int,
                         b: float) -> np.ndarray:
    """A shared hidden layer's output weights at brackets (i, i1, a) of the gain and
    (j, j1, b) of the noise, as :meth:`GainTableMap.weights` makes them, shape (1, 1,
    n_out, H + 1) (the kernels' ``coef`` with one grid point)."""
    n_out, n = coef.shape[2], coef.shape[3]
    out = np.empty((1, 1, n_out, n))
    for o in range(n_out):
        for k in range(n):
            lo = (1 - b) * coef[i, j, o, k] + b * coef[i, j1, o, k]
            hi = (1 - b) * coef[i1, j, o, k] + b * coef[i1, j1, o, k]
            out[0, 0, o, k] = (1 - a) * lo + a * hi
    return out
