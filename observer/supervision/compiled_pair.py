"""A pair of photodiodes with the two-Gaussian response, compiled: its shape inversion and
the variance of the phi it gives (``ledsim.radiometry.optics.pair_shape_inverse`` and
``pair_phi_variance`` stay the reference and call these when :func:`observer.jit.enabled`),
and the fading channel's and the gain tracker's steps built on them
(:mod:`observer.supervision.compiled_gain`). The same formulas in the same order;
np.interp is a binary search on the same table. A receiver passes its numbers as
``shape``: (the shape table log(g1 / g2), its phis [rad], the response's (a1, b1, c1,
a2, b2, c2), dphi [rad])."""

from __future__ import annotations

import math

import numpy as np

from observer.jit import njit


@njit()
def response_and_slope(phi: float, a1: float, b1: float, c1: float, a2: float, b2: float,
                       c2: float) -> tuple[float, float]:
    """(g(phi), dg/dphi) of the two-Gaussian response (optics.response_terms)."""
    u1, u2 = (phi - b1) / c1, (phi + b2) / c2
    e1, e2 = a1 * math.exp(-(u1 * u1)), a2 * math.exp(-(u2 * u2))
    return e1 + e2, -2 * u1 / c1 * e1 - 2 * u2 / c2 * e2


@njit()
def _interp(x: float, xp: np.ndarray, fp: np.ndarray) -> float:
    """np.interp for one x on increasing ``xp``."""
    n = xp.size
    if not x >= xp[0]:  # below, or NaN (numpy gives NaN for NaN: handled by the caller)
        return fp[0]
    if x >= xp[n - 1]:
        return fp[n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if xp[mid] <= x:
            lo = mid
        else:
            hi = mid
    slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo])
    return slope * (x - xp[lo]) + fp[lo]


@njit()
def shape_inverse(p1: float, p2: float, table: np.ndarray, phis: np.ndarray, a1: float,
                  b1: float, c1: float, a2: float, b2: float, c2: float,
                  dphi: float) -> tuple[float, float, float]:
    """optics.pair_shape_inverse of the powers (p1, p2) [W], both > 0."""
    ratio = math.log(p1 / p2)
    phi = math.nan if ratio != ratio else _interp(ratio, table, phis)
    g1, dg1 = response_and_slope(phi, a1, b1, c1, a2, b2, c2)
    g2, dg2 = response_and_slope(phi + dphi, a1, b1, c1, a2, b2, c2)
    gain = (p1 * g1 + p2 * g2) / (g1 * g1 + g2 * g2)
    d1, d2 = gain * dg1, gain * dg2
    det = d1 * g2 - d2 * g1
    if det == 0 or gain <= 0:
        return phi, gain, math.inf
    return phi, gain, (d1 * d1 + d2 * d2) / det**2 / gain**2


@njit()
def pair_inverse(pair: np.ndarray, table: np.ndarray, phis: np.ndarray, a1: float,
                 b1: float, c1: float, a2: float, b2: float, c2: float,
                 dphi: float) -> tuple[float, float, float]:
    """:func:`shape_inverse` of a pair of powers [W] held as an array: the pair's formula
    reads its two photodiodes by position, as the reference's does (optics.py)."""
    return shape_inverse(pair[0], pair[1], table, phis, a1, b1, c1, a2, b2, c2, dphi)


@njit()
def phi_variance(phi: float, powers: np.ndarray, noise_std: float, a1: float, b1: float,
                 c1: float, a2: float, b2: float, c2: float, dphi: float) -> float:
    """optics.pair_phi_variance [rad^2]."""
    g1, dg1 = response_and_slope(phi, a1, b1, c1, a2, b2, c2)
    g2, dg2 = response_and_slope(phi + dphi, a1, b1, c1, a2, b2, c2)
    slope = dg1 / g1 - dg2 / g2
    if slope == 0:
        return math.inf
    inv = 0.0
    for p in powers:
        inv += 1.0 / (p * p)
    return noise_std * noise_std * inv / (slope * slope)
