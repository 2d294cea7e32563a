"""The gain tracker's step and the fading channel's, compiled
(:class:`~observer.supervision.gain_tracking.GainTracker` and
:class:`~observer.supervision.fading.FadingChannel` stay the reference: they call these
when their receiver gives its pair's numbers, ``shape``, as in
:mod:`observer.supervision.compiled_pair`). The reference's memory goes in as an array and
comes back in it; the same formulas in the same order."""

from __future__ import annotations

import math

import numpy as np

from observer.jit import njit
from observer.supervision.compiled_pair import pair_inverse, phi_variance

#: FadingChannel's memory as the kernel takes it: the last sample is kept, its log-gain,
#: its phi, its encoder angle, whether it had one; the pairs learned from; the four
#: variances.
FADING_STATE = ("kept", "log_gain", "phi", "q", "has_q", "learned", "step_variance",
                "noise_variance", "shape_step_variance", "shape_noise_variance")


@njit()
def _excess(step_variance: float, noise_variance: float) -> float:
    excess = 0.5 * step_variance - noise_variance
    return excess if excess > noise_variance else 0.0


@njit()
def fading_sample(y, q, has_q, sigma, ratio, min_snr, model_gain, max_variance, alpha,
                  min_learned, shapes, table, phis, a1, b1, c1, a2, b2, c2, dphi,
                  memory) -> float:
    """FadingChannel.sample: the fade [-]; ``memory`` (:data:`FADING_STATE`) in place.
    ``shapes``: the shape's fading is learned (a phi variance is given)."""
    for i in range(y.size):
        if not (np.isfinite(y[i]) and y[i] > min_snr * sigma[i]):
            memory[0] = 0.0
            return 1.0
    phi, gain, v = pair_inverse(y, table, phis, a1, b1, c1, a2, b2, c2, dphi)
    if not (np.isfinite(gain) and gain > 0 and np.isfinite(v)):
        memory[0] = 0.0
        return 1.0
    var = 0.0
    for sg in sigma:
        var += sg * sg
    var /= sigma.size
    log_gain, noise = math.log(gain / model_gain), v * var
    if noise > max_variance:
        memory[0] = 0.0
        return 1.0
    kept, last_lg, last_phi, last_q, last_has_q = memory[0], memory[1], memory[2], memory[3], \
        memory[4]
    memory[0], memory[1], memory[2], memory[3], memory[4] = 1.0, log_gain, phi, q, has_q
    if kept == 0.0:
        return 1.0
    memory[5] += 1
    a = max(alpha, 1.0 / memory[5])
    step, nv = memory[6], memory[7]
    floor = 2 * (nv if nv != 0.0 else noise)
    memory[6] = step + a * (min((log_gain - last_lg) ** 2, 9.0 * max(step, floor)) - step)
    memory[7] = nv + a * (noise - nv)
    if has_q and last_has_q != 0.0 and shapes:
        phi_noise = phi_variance(phi, y, math.sqrt(var), a1, b1, c1, a2, b2, c2, dphi)
        if np.isfinite(phi_noise):
            moved = (phi - last_phi) + (q - last_q)
            ss, sn = memory[8], memory[9]
            floor = 2 * (sn if sn != 0.0 else phi_noise)
            memory[8] = ss + a * (min(moved * moved, 9.0 * max(ss, floor)) - ss)
            memory[9] = sn + a * (phi_noise - sn)
    fading = _excess(memory[6], memory[7]) if memory[5] >= min_learned else 0.0
    if fading > 0.0:
        share = fading / (fading + noise)
        return math.exp(share * (log_gain - math.log(ratio)))
    return 1.0


@njit()
def gain_update(y, sigma, memory, powers, Te, q00, q01, q11, alpha, min_snr, model_gain,
                fading, max_variance, deadband, deadband_moving, table, phis, a1, b1, c1,
                a2, b2, c2, dphi) -> bool:
    """GainTracker.update on ``memory`` (log ratio, its rate, P00, P01, P11, the averaged
    powers exist, their lag [s], the ratio) and the averaged ``powers``, in place.
    Returns whether the sample was finite (the reference then keeps its ``sigma``)."""
    s0, s1, p00, p01, p11 = memory[0], memory[1], memory[2], memory[3], memory[4]
    s0 += Te * s1
    p00, p01 = p00 + 2 * Te * p01 + Te * Te * p11 + q00, p01 + Te * p11 + q01
    p11 += q11
    memory[0], memory[1], memory[2], memory[3], memory[4] = s0, s1, p00, p01, p11
    for v in y:
        if not np.isfinite(v):
            return False
    a = alpha
    if memory[5] == 0.0:
        powers[:] = y
        memory[5], memory[6] = 1.0, 0.0
    else:
        for i in range(y.size):
            powers[i] = (1 - a) * powers[i] + a * y[i]
        memory[6] = (1 - a) * (memory[6] + Te)
    for i in range(y.size):
        if not powers[i] > min_snr * sigma[i]:
            return True
    _, gain, v = pair_inverse(powers, table, phis, a1, b1, c1, a2, b2, c2, dphi)
    if not (np.isfinite(gain) and gain > 0 and np.isfinite(v)):
        return True
    var = 0.0
    for sg in sigma:
        var += sg * sg
    r = v * var / sigma.size
    if fading:
        r += fading * a / (2 - a)
    if r > max_variance:
        return True
    lag = memory[6]
    h0, h1 = p00 - lag * p01, p01 - lag * p11
    den = h0 - lag * h1 + r
    k0, k1 = h0 / den, h1 / den
    innovation = math.log(gain / model_gain) - (s0 - lag * s1)
    memory[0], memory[1] = s0 + k0 * innovation, s1 + k1 * innovation
    memory[2], memory[3], memory[4] = p00 - k0 * h0, p01 - k0 * h1, p11 - k1 * h1
    moving = abs(memory[1]) > 3 * math.sqrt(memory[4])
    est = math.exp(memory[0])
    band = deadband_moving if moving else deadband
    memory[7] = min(max(memory[7], est / (1 + band)), est / (1 - band))
    return True
