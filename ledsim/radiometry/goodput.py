"""Goodput: the data a run delivers through the link's forward-error-correcting code.

The data rides on the data detector (the pair's ``pd1``, the quad's boresight ``pd0``),
on-off keyed at the run's bit rate (:mod:`ledsim.radiometry.data_channel`: each step's
SNR and BER from its noise-free power). The code is a binary BCH code of length
n = 2^15 - 1 = 32767 bits correcting t = 160 errors, k = n - 15 t = 30367 data bits (7.9 %
overhead on the data): hard-decision FEC of the 7 % class whose threshold the link budget's
:data:`~ledsim.radiometry.data_channel.FEC_LIMIT` (3.8e-3) is (ITU-T G.975.1, whose 7 %
codes reach an output BER of 1e-15 there). A frame is lost when more than t of its n
bits are wrong, so at the step's BER p

    FER(p) = P[Binomial(n, p) > t]

(9e-4 at 3.8e-3, 0.14 at 4.5e-3, 0.6 at 5e-3: the code's waterfall), and a step of Te
delivers R_b Te (k / n) (1 - FER) bits: its frames' share that decodes, at that step's
BER (a frame spans several steps at these rates; each step is counted at its own BER).

A run counts a step's bits only while its supervisor holds the link (neither lost nor
acquiring: the acquisition's time is lost); unsupervised, every step. The ideal is the
same path pointed perfectly: every step at the most the geometry allows the data
detector (:func:`~ledsim.loop.outcome.achievable_power`). An outage is a stretch of
steps, after the first acquisition, that deliver under half of what the code carries
(a frame in two lost, or the link not held).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ledsim.radiometry.data_channel import ber_ook, snr_at
from observer.noise import MeasurementNoise

#: The FEC code: n bits a frame, t errors corrected, k data bits (a BCH code over
#: GF(2^15): 15 parity bits per corrected error).
CODE_N, CODE_T = 32767, 160
CODE_K = CODE_N - 15 * CODE_T
#: A step delivering under this share of the code's rate is in an outage [-].
OUTAGE_SHARE = 0.5
#: The farthest share of the range the ideal delivers over that counts as its edge
#: (issue 49: a fly-by's first and last 20 % of range) [-].
EDGE_SHARE = 0.2


def _log_choose(k: np.ndarray) -> np.ndarray:
    return np.array([math.lgamma(CODE_N + 1) - math.lgamma(j + 1)
                     - math.lgamma(CODE_N - j + 1) for j in k.tolist()])


def _log_terms(k: np.ndarray, choose: np.ndarray, p: np.ndarray) -> np.ndarray:
    """log P[Binomial(n, p) = k], rows p (M, 1), columns k (log C(n, k): ``choose``)."""
    return choose + k * np.log(p) + (CODE_N - k) * np.log1p(-p)


def _sum_exp(logs: np.ndarray) -> np.ndarray:
    top = logs.max(axis=-1, keepdims=True)
    return np.exp(top[..., 0]) * np.exp(logs - top).sum(axis=-1)


_BELOW, _ABOVE = np.arange(CODE_T + 1), np.arange(CODE_T + 1, CODE_T + 801)
_CHOOSE_BELOW, _CHOOSE_ABOVE = _log_choose(_BELOW), _log_choose(_ABOVE)


def frame_error_rate(ber) -> np.ndarray:
    """FER [-] of the code at each bit error rate ``ber`` [-]: P[Binomial(n, p) > t],
    summed exactly in logs (the tail itself where it is small, so that a clean link's
    FER is not the round-off of 1 - (1 - FER))."""
    shape = np.shape(ber)
    p = np.clip(np.atleast_1d(np.asarray(ber, dtype=float)), 0.0, 0.5)
    out = np.zeros(p.shape)
    small = (p > 0) & (p * CODE_N < CODE_T)  # the tail beyond t + 800 is nothing there
    large = p * CODE_N >= CODE_T
    if small.any():
        # Below t the terms fall with k, so the first is the largest; where its log is
        # under -800 the sum is 0.0 in float64 (exp underflows at -745): not summed.
        first = _log_terms(_ABOVE[:1], _CHOOSE_ABOVE[:1], p[small][..., None])[..., 0]
        small[small] = first >= -800.0
        out[small] = _sum_exp(_log_terms(_ABOVE, _CHOOSE_ABOVE, p[small][..., None]))
    if large.any():
        out[large] = 1.0 - _sum_exp(_log_terms(_BELOW, _CHOOSE_BELOW, p[large][..., None]))
    return np.clip(out.reshape(shape), 0.0, 1.0)


def delivered_bits(power, noise: MeasurementNoise, Te: float, bit_rate: float
                   ) -> np.ndarray:
    """Data bits each step of ``Te`` [s] delivers through the code, at the data
    detector's noise-free ``power`` [W] that step and the run's ``noise``."""
    ber = ber_ook(snr_at(power, noise, Te, bit_rate))
    return bit_rate * Te * (CODE_K / CODE_N) * (1.0 - frame_error_rate(ber))


@dataclass
class Goodput:
    """What a run delivered.

    Attributes:
        goodput_bits: data bits delivered while the link was held [bit].
        ideal_bits: what the same path delivers pointed perfectly [bit].
        outages: stretches after the first acquisition delivering under half the code's
            rate (:data:`OUTAGE_SHARE`) [-].
        outage_s: their total length [s].
        range_m: the range's span over the run, [nearest, farthest] [m].
        edge_goodput_bits, edge_ideal_bits: the same two where the data can be lost,
            near the edge of the range the ideal delivers at: the steps it delivers
            at over half the code's rate whose range is in the farthest
            :data:`EDGE_SHARE` of that span (a fly-by's first and last stretch of
            link) [bit] (None without ranges).
    """

    goodput_bits: float
    ideal_bits: float
    outages: int
    outage_s: float
    range_m: list
    edge_goodput_bits: float | None = None
    edge_ideal_bits: float | None = None


def goodput(power, best, noise: MeasurementNoise, Te: float, bit_rate: float,
            held=None, distance=None) -> Goodput:
    """The :class:`Goodput` of a run: the data detector's noise-free ``power`` and the
    most the geometry allowed it, ``best``, each step [W]; ``held``: the steps the
    supervisor held the link (None: every step); ``distance``: the range each step [m]."""
    bits = delivered_bits(power, noise, Te, bit_rate)
    ideal = delivered_bits(best, noise, Te, bit_rate)
    held = np.ones(len(bits), bool) if held is None else np.asarray(held, bool)
    got = np.where(held, bits, 0.0)
    low = got < OUTAGE_SHARE * bit_rate * Te * CODE_K / CODE_N
    start = int(np.argmax(held)) if held.any() else len(low)
    low[:start] = False  # the first acquisition is not an outage
    edges = np.diff(np.r_[0, low.astype(np.int8), 0])
    d = np.asarray(distance, float) if distance is not None else np.zeros(0)
    edge = None
    full = ideal >= OUTAGE_SHARE * bit_rate * Te * CODE_K / CODE_N  # the ideal delivers
    if d.size and full.any():
        near, far = float(d[full].min()), float(d[full].max())
        at = full & (d >= far - EDGE_SHARE * (far - near))
        edge = float(got[at].sum()), float(ideal[at].sum())
    return Goodput(float(got.sum()), float(ideal.sum()), int((edges == 1).sum()),
                   float(low.sum() * Te),
                   [float(d.min()), float(d.max())] if d.size else [],
                   *(edge or (None, None)))
