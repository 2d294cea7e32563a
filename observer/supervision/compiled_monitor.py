"""The residual monitor's update, compiled (:class:`~observer.supervision.monitor.ResidualMonitor`
stays the reference and calls it when its model gives its ``h`` as numbers,
``compiled_h``). The state lives in arrays the kernel updates in place."""

from __future__ import annotations

import math

import numpy as np

from observer.jit import njit
from observer.supervision.compiled_pair import response_and_slope

#: The reasons the kernel returns, by code (0: not lost; 3: no usable sample, the last
#: decision stands).
REASONS = ("", "non-finite estimate", "estimate outside the domain", None,
           "output residual above the noise", "no light")


@njit()
def response_power(phi: float, gain: float, offsets: np.ndarray,
                   response: np.ndarray) -> np.ndarray:
    """h of a one-axis model whose photodiodes sit at ``offsets`` [rad]: gain x g(phi + o)
    with the two-Gaussian g of ``response`` (a1, b1, c1, a2, b2, c2)."""
    out = np.empty(offsets.size)
    for i in range(offsets.size):
        g, _ = response_and_slope(phi + offsets[i], response[0], response[1], response[2],
                                  response[3], response[4], response[5])
        out[i] = gain * g
    return out


@njit()
def update(y, xh, gain, offsets, response, y_lo, y_hi, bounded, low, high, floor,
           mean_residual, noise_var, y_prev, mean_x, bright, counters, alpha, noise_alpha,
           domain_alpha, threshold, model_error, dark_sigmas):
    """ResidualMonitor.update: the reason's code (:data:`REASONS`). ``counters`` holds
    (a previous sample is kept, the averaged estimate exists, samples in ``bright``,
    the ring's next slot, the statistic)."""
    n = y.size
    ok = np.empty(n, np.bool_)
    for i in range(n):
        v = y[i]
        ok[i] = np.isfinite(v) and (not bounded or (y_lo[i] <= v <= y_hi[i]))
    if counters[0] > 0:  # the noise level from successive differences
        a = noise_alpha
        for i in range(n):
            d2 = 0.5 * (y[i] - y_prev[i]) ** 2 if ok[i] and np.isfinite(y_prev[i]) \
                else noise_var[i]
            noise_var[i] = max((1 - a) * noise_var[i] + a * d2, floor[i])
    for i in range(n):
        y_prev[i] = y[i] if ok[i] else math.nan
    counters[0] = 1.0
    for v in xh:
        if not np.isfinite(v):
            return 1
    if counters[1] == 0:
        mean_x[:] = xh
        counters[1] = 1.0
    else:
        b = domain_alpha
        for i in range(xh.size):
            mean_x[i] = (1 - b) * mean_x[i] + b * xh[i]
    for i in range(xh.size):
        if mean_x[i] < low[i] or mean_x[i] > high[i]:
            return 2
    if not ok.any():
        return 3
    yhat = response_power(xh[0], gain, offsets, response)
    a, statistic = alpha, 0.0
    for i in range(n):
        if ok[i]:
            mean_residual[i] = (1 - a) * mean_residual[i] + a * (y[i] - yhat[i])
        spread2 = noise_var[i] * a / (2 - a) + (model_error * yhat[i]) ** 2
        statistic += mean_residual[i] ** 2 / spread2
    counters[4] = statistic
    if statistic > threshold:
        return 4
    brightest = -math.inf
    for i in range(n):
        if ok[i] and y[i] > brightest:
            brightest = y[i]
    steps = bright.size  # a ring of the last dark_steps brightest powers
    bright[int(counters[3])] = brightest
    counters[3] = (counters[3] + 1) % steps
    counters[2] = min(counters[2] + 1, steps)
    if counters[2] < steps:
        return 0
    total, k = 0.0, int(counters[3])
    for _ in range(steps):  # oldest first, as the reference's list sums
        total += bright[k]
        k = (k + 1) % steps
    if total / steps <= dark_sigmas * math.sqrt(noise_var.max() / steps):
        return 5
    return 0
