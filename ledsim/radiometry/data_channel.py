"""What a communications engineer asks first of a run: SNR, bit error rate, data
delivered, and the share of time a forward-error-correcting code can clean the bits.

The data rides on photodiode 1, on-off keyed (OOK, non-return-to-zero) at
:data:`BIT_RATE`. Each control step it receives the noise-free power P1 [W] of that
step; the noise is the sensor's own (``LinkConstants.measurement_noise_std`` times the
run's noise scale, specified over the bandwidth 1 / (2 Te) of one sample) spread over
the data's bandwidth, R_b / 2:

    SNR     = P1^2 / sigma_b^2,     sigma_b^2 = sigma^2 (R_b / 2) / (1 / (2 Te))
                                              = sigma^2 R_b Te
    BER     = Q(sqrt(SNR) / 2) = erfc(sqrt(SNR) / (2 sqrt 2)) / 2

the error probability of equiprobable "on" (P1) and "off" (0) levels with the decision
threshold half-way, in Gaussian noise (Proakis and Salehi, *Digital Communications*,
5th ed., section 4.2, binary PAM with levels 0 and A). A step delivers its R_b Te bits
when its BER is below the forward-error-correction limit :data:`FEC_LIMIT` = 3.8e-3,
the threshold of 7 % overhead hard-decision FEC that underwater optical link experiments
report against (e.g. "Monocular vision aided optical tracking for underwater optical
wireless communications", Optics Express 30(9), 2022).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ledsim.files.results import DictAccess
from observer.noise import MeasurementNoise

#: Data rate of the link [bit/s]. The paper's measurement noise (sigma = 0.032 W on a
#: 1 W peak, 30 dB over one 50 Hz sample) sets the scale: at 1 kbit/s an aligned link
#: has an SNR of about 20 dB and a BER of 1e-6. A receiver with a lower noise floor
#: carries proportionally more (the SNR scales as 1 / R_b).
BIT_RATE = 1e3
#: BER below which forward error correction delivers the bits [-].
FEC_LIMIT = 3.8e-3

_erfc = np.frompyfunc(math.erfc, 1, 1)


def snr(power: np.ndarray, noise_std: float, Te: float, bit_rate: float = BIT_RATE
        ) -> np.ndarray:
    """Electrical SNR [-] of OOK at ``bit_rate`` [bit/s] for received powers [W] and the
    sensor noise ``noise_std`` [W] of one sample of period ``Te`` [s]."""
    p = np.maximum(np.asarray(power, dtype=float), 0.0)
    return p * p / (noise_std * noise_std * bit_rate * Te)


def ber_ook(snr_values: np.ndarray) -> np.ndarray:
    """Bit error rate [-] of OOK at the given SNRs: Q(sqrt(SNR) / 2)."""
    x = np.sqrt(np.asarray(snr_values, dtype=float)) / (2.0 * math.sqrt(2.0))
    return 0.5 * np.asarray(_erfc(x), dtype=float)


@dataclass
class LinkBudget(DictAccess):
    """A run's link budget.

    Attributes:
        snr_db: the run's mean SNR, in dB (10 log10 of the mean of the steps' SNRs;
            None when no light arrived at all).
        ber: the run's bit error rate: the mean of the steps' BERs [-].
        throughput_bps: bits delivered (steps under the FEC limit) per second of run.
        fec_share: share of the steps whose BER is under the FEC limit [-].
    """

    snr_db: float | None
    ber: float
    throughput_bps: float
    fec_share: float


def link_budget(power: np.ndarray, noise_std: float, Te: float,
                bit_rate: float = BIT_RATE) -> LinkBudget:
    """The link budget of a run from photodiode 1's noise-free power at each step [W]."""
    return _budget(snr(power, noise_std, Te, bit_rate), bit_rate)


def _budget(s: np.ndarray, bit_rate: float) -> LinkBudget:
    """The budget of the steps' SNRs ``s`` [-] at ``bit_rate`` [bit/s]."""
    ber = ber_ook(s)
    ok = ber < FEC_LIMIT
    mean_snr = float(np.mean(s))
    return LinkBudget(10.0 * math.log10(mean_snr) if mean_snr > 0 else None,
                      float(np.mean(ber)), bit_rate * float(np.mean(ok)),
                      float(np.mean(ok)))


def data_channel(noise: MeasurementNoise, Te: float, bit_rate: float = BIT_RATE
                 ) -> MeasurementNoise:
    """The data channel's noise: the pointing channel's ``noise`` (one sample of period
    ``Te`` [s], bandwidth 1 / (2 Te)) over the data's bandwidth R_b / 2, no ADC."""
    return noise.at_bandwidth(bit_rate * Te)


def q_factor(power, data_noise: MeasurementNoise) -> np.ndarray:
    """Q = P / (sigma_on + sigma_off) [-] of OOK between P [W] and 0, whose noise
    ``data_noise`` depends on the level (shot noise on "on" only); BER = Q(Q-factor)
    with the threshold where the two levels' errors balance (Personick's form)."""
    p = np.maximum(np.asarray(power, dtype=float), 0.0)
    return p / (data_noise.analog_std(p) + data_noise.analog_std(0.0))


def snr_at(power, noise: MeasurementNoise, Te: float, bit_rate: float = BIT_RATE
           ) -> np.ndarray:
    """Electrical SNR [-] of OOK at ``bit_rate`` for received powers [W]: (2 Q)^2, which
    is P^2 / sigma_b^2 (:func:`snr`) when the noise does not depend on the signal."""
    if not noise.signal_dependent:
        return snr(power, noise.std, Te, bit_rate)
    return (2.0 * q_factor(power, data_channel(noise, Te, bit_rate))) ** 2


def link_budget_of(power: np.ndarray, noise: MeasurementNoise, Te: float,
                   bit_rate: float = BIT_RATE) -> LinkBudget:
    """:func:`link_budget` with the run's noise object: the paper's formula when the
    noise does not depend on the signal (the same numbers), shot noise otherwise."""
    if not noise.signal_dependent:
        return link_budget(power, noise.std, Te, bit_rate)
    return _budget(snr_at(power, noise, Te, bit_rate), bit_rate)
