"""The gain-scheduled KKL's step, compiled: its update in one call, its predict in one.

:class:`~observer.kkl.scheduled.ScheduledKKL` stays the reference; these kernels do what
its ``_estimate``, ``update`` and the filter half of ``predict`` do, in the same order of
operations, with the maps of :mod:`observer.kkl.compiled_maps`. What happens rarely (a
restart of the gain inside ``_estimate``, a missing sample, a change of gain) goes back
to the reference's Python.
"""

from __future__ import annotations

import numpy as np

from observer.jit import njit
from observer.kkl.compiled_maps import _hidden as _hidden_of
from observer.kkl.compiled_maps import _output, map_rows


@njit()
def _bracket(grid: np.ndarray, v: float) -> tuple[int, float]:
    """:func:`observer.kkl.gainmaps._bracket`: v at (1 - t) grid[i] + t grid[i + 1]."""
    n = grid.size
    if n == 1:
        return 0, 0.0
    v = min(max(v, grid[0]), grid[n - 1])
    i = 0
    while i < n - 2 and grid[i + 1] <= v:  # searchsorted(side="right") - 1, at most n - 2
        i += 1
    return i, (v - grid[i]) / (grid[i + 1] - grid[i])


@njit()
def decode(z: np.ndarray, w: float, s: float, W1T: np.ndarray, b1: np.ndarray,
           coef: np.ndarray, log_w: np.ndarray, log_s: np.ndarray) -> np.ndarray:
    """A per-gain :class:`~observer.kkl.gainmaps.GainTableMap` (a decoder) at gain ``w``
    and noise ``s`` on one sample ``z``."""
    i, a = _bracket(log_w, np.log(w))
    j, b = _bracket(log_s, np.log(s))
    out = np.empty((1, coef.shape[2]))
    map_rows(z.reshape(1, z.size), W1T, b1, coef, i, min(i + 1, coef.shape[0] - 1), a, j,
             min(j + 1, coef.shape[1] - 1), b, False, out)
    return out[0]


@njit()
def _box_distance(x: np.ndarray, centre: np.ndarray, half: np.ndarray) -> float:
    """max_i |x_i - centre_i| / half_i [-], NaN if any is."""
    worst = 0.0
    for i in range(x.size):
        d = abs(x[i] - centre[i]) / half[i]
        if d != d:
            return np.nan
        if i == 0 or d > worst:
            worst = d
    return worst


@njit()
def estimate(z, w, noise, dec_W1T, dec_b1, dec_coef, dec_log_w, dec_log_s, locked_maps,
             loc_W1T, loc_b1, loc_coef, loc_log_w, loc_log_s, centre, half, off, inside,
             Te, settle_off, jump, box, recover_gain, slowest, lock_after, lock_ramp,
             disagree):
    """ScheduledKKL._estimate: (x, off, inside, locked, wide, restart). With
    ``restart`` True nothing is decided: the gain must restart first (the caller's)."""
    x = decode(z, w, noise, dec_W1T, dec_b1, dec_coef, dec_log_w, dec_log_s)
    d = _box_distance(x, centre, half)
    off += min(Te / settle_off, 1.0) * (d - off)
    jumped = d > jump * box
    wide = off > box or jumped
    if wide and w < recover_gain:
        return x, off, inside, 0.0, wide, True
    if off > 0.75 * box or jumped:
        inside = 0.0
    elif off <= 0.5 * box:
        inside += Te
    memory = lock_after / slowest
    locked = 0.0
    if locked_maps:
        locked = min(max((inside - memory) / lock_ramp, 0.0), 1.0)
    if locked > 0:
        near = decode(z, w, noise, loc_W1T, loc_b1, loc_coef, loc_log_w, loc_log_s)
        if _box_distance(near, x, half) > disagree:
            inside, locked = 0.0, 0.0
        else:
            x = x + locked * (near - x)
    return x, off, inside, locked, wide, False


@njit()
def checks(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, y: np.ndarray, y_lo: np.ndarray,
           y_hi: np.ndarray, bounded: bool) -> tuple[bool, bool]:
    """(x inside the training box [lo, hi], every sample of y usable: finite and, when
    ``bounded``, within [y_lo, y_hi])."""
    inside = True
    for i in range(x.size):
        if not (lo[i] <= x[i] <= hi[i]):
            inside = False
    usable = True
    for i in range(y.size):
        v = y[i]
        if not np.isfinite(v) or (bounded and not (y_lo[i] <= v <= y_hi[i])):
            usable = False
    return inside, usable


@njit()
def filter_step(z, a, y, channel, omega, xh, u, u_bar, coef_phi, coef_rate, lo, hi,
                enc_W1T, enc_b1, enc_C):
    """ScheduledKKL.predict's filters and Omega on one axis: (the new z, whether the
    driven state left the training box). ``omega``: u differs from u_bar and Omega is
    on; the one-step model is the identified one (coefficients ``coef_phi``,
    ``coef_rate``); ``enc_C`` is the shared encoder's output weights at the current gain,
    shape (1, 1, q, H + 1)."""
    q = z.size
    out = np.empty(q)
    for i in range(q):
        out[i] = z[i] + a[i] * (y[channel[i]] - z[i])
    if not omega:
        return out, False
    rows = np.empty((2, 2))
    phi, rate = xh[0], xh[1]
    a1, a2, a3 = coef_phi[0], coef_phi[1], coef_phi[2]
    b1, b2, b3 = coef_rate[0], coef_rate[1], coef_rate[2]
    drag = abs(rate) * rate
    rows[0, 0] = phi + (a1 * rate + a2 * u + a3 * drag)
    rows[0, 1] = b1 * rate + b2 * u + b3 * drag
    rows[1, 0] = phi + (a1 * rate + a2 * u_bar + a3 * drag)
    rows[1, 1] = b1 * rate + b2 * u_bar + b3 * drag
    outside = not (lo[0] <= rows[0, 0] <= hi[0] and lo[1] <= rows[0, 1] <= hi[1])
    both = np.empty((2, q))
    map_rows(rows, enc_W1T, enc_b1, enc_C, 0, 0, 0.0, 0, 0, 0.0, True, both)
    for i in range(q):
        out[i] = out[i] + both[0, i] - both[1, i]
    return out, outside


@njit()
def gain_change(z: np.ndarray, x: np.ndarray, w: float, w_old: float, W1T: np.ndarray,
                b1: np.ndarray, coef: np.ndarray, log_w: np.ndarray,
                restart: bool) -> np.ndarray:
    """ScheduledKKL.set_gain's new z for a shared encoder: ``z + T(x; w) - T(x; w_old)``,
    or ``T(x; w)`` on a restart; the hidden layer of x is evaluated once for both."""
    q = z.size
    h = np.empty(b1.shape[1])
    bits = np.empty(b1.shape[1], np.int64)
    _hidden_of(x, W1T[0], b1[0], h, bits)
    new = np.zeros(q)
    i, a = _bracket(log_w, np.log(w))
    _output(coef, i, min(i + 1, coef.shape[0] - 1), a, 0, 0, 0.0, h, 1.0, new)
    if restart:
        return new
    old = np.zeros(q)
    i, a = _bracket(log_w, np.log(w_old))
    _output(coef, i, min(i + 1, coef.shape[0] - 1), a, 0, 0, 0.0, h, 1.0, old)
    out = np.empty(q)
    for k in range(q):
        out[k] = z[k] + new[k] - old[k]
    return out


@njit()
def rate_vector(slowest: float, fastest: float, n_rates: int, n_output: int,
                w: float) -> np.ndarray:
    """ScheduledDesign.rate_vector: rates from ``slowest w`` to ``fastest`` [1/s], evenly
    in log, for each output."""
    lo = slowest * w
    out = np.empty(n_rates * n_output)
    step = 1.0 / (n_rates - 1)
    for k in range(n_rates):  # the fractions as numpy's linspace makes them
        r = lo * (fastest / lo) ** (k * step if k < n_rates - 1 else 1.0)
        for o in range(n_output):
            out[o * n_rates + k] = r
    return out
