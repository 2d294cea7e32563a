"""The link budget against distance: SNR, BER, throughput and FEC share, and the range
at the FEC limit (``ledsim budget``).

The link is aligned on both ends but for an optional Gaussian pointing error of the
receiver (``pointing_error`` [rad]): the FEC share is then the share of pointing errors
under which the BER stays under the FEC limit, and the throughput the bit rate times it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ledsim.constants import LinkConstants
from ledsim.files.results import DictAccess
from ledsim.radiometry.data_channel import FEC_LIMIT, ber_ook, snr_at
from ledsim.radiometry.optics import receiver_response, transmitter_gain

_NODES, _WEIGHTS = np.polynomial.hermite_e.hermegauss(41)
_WEIGHTS = _WEIGHTS / _WEIGHTS.sum()


def peak_response(c: LinkConstants) -> tuple[float, float]:
    """(phi*, g(phi*)): the receiver's best incidence angle [rad] and its response."""
    phi = np.linspace(-0.6, 0.6, 12001)
    g = receiver_response(phi, c.receiver)
    k = int(np.argmax(g))
    return float(phi[k]), float(g[k])


def aligned_power(c: LinkConstants, distance) -> np.ndarray:
    """Photodiode 1's power [W] at ``distance`` [m] with both ends aligned."""
    return transmitter_gain(distance, 0.0, c) * peak_response(c)[1]


@dataclass
class BudgetRow(DictAccess):
    """The budget at one distance (units in the names)."""

    distance_m: float
    received_power_w: float
    snr_db: float | None
    ber: float
    throughput_bps: float
    fec_share: float


def budget_at(c: LinkConstants, distance: float, bit_rate: float,
              pointing_error: float = 0.0) -> BudgetRow:
    """The budget at ``distance`` [m] and ``bit_rate`` [bit/s] with a Gaussian pointing
    error of standard deviation ``pointing_error`` [rad]."""
    noise = c.measurement_noise()
    phi0, g0 = peak_response(c)
    gain = float(transmitter_gain(distance, 0.0, c))
    phis = phi0 + pointing_error * _NODES
    power = gain * receiver_response(phis, c.receiver)
    s = snr_at(power, noise, c.Te, bit_rate)
    ber = ber_ook(s)
    share = float(np.sum(_WEIGHTS * (ber < FEC_LIMIT)))
    aligned = float(snr_at(np.array([gain * g0]), noise, c.Te, bit_rate)[0])
    return BudgetRow(distance, gain * g0, 10 * math.log10(aligned) if aligned > 0 else None,
                     float(np.sum(_WEIGHTS * ber)), bit_rate * share, share)


def range_at_fec(c: LinkConstants, bit_rate: float, lo: float = 1e-3, hi: float = 2000.0
                 ) -> float:
    """The longest distance [m] at which the aligned link's BER is under the FEC limit
    (bisection in log distance; ``lo`` when even that fails, ``hi`` when it never does)."""
    def fails(d: float) -> bool:
        s = snr_at(aligned_power(c.with_(distance=d), np.array([d])), c.measurement_noise(),
                   c.Te, bit_rate)
        return bool(ber_ook(s)[0] >= FEC_LIMIT)

    if fails(lo):
        return lo
    if not fails(hi):
        return hi
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if fails(mid) else (mid, hi)
    return math.sqrt(lo * hi)


@dataclass
class BudgetReport(DictAccess):
    """``ledsim budget``'s answer (units in the names).

    Attributes:
        link, water: the preset and the water's name.
        attenuation_per_m: the attenuation the power law uses [1/m] (the effective one
            for a physical link, the beam attenuation c for the paper's bench).
        beam_attenuation_per_m: the water's c at the link's wavelength [1/m].
        bit_rate: [bit/s]; fec_limit: the BER the FEC limit is set at [-].
        pointing_error_rad: the receiver's Gaussian pointing error [rad].
        range_at_fec_limit_m: the longest aligned distance with BER under the limit [m].
        rows: the budget at each distance.
    """

    link: str
    water: str
    attenuation_per_m: float
    beam_attenuation_per_m: float
    bit_rate: float
    fec_limit: float
    pointing_error_rad: float
    range_at_fec_limit_m: float
    rows: list


def budget_report(name: str, water: str | None = None, attenuation: float | None = None,
                  bit_rate: float | None = None, distances=None,
                  pointing_error: float = 0.0) -> BudgetReport:
    """The link budget of preset ``name`` in ``water`` (or at beam attenuation
    ``attenuation`` [1/m]) at ``bit_rate`` [bit/s] (default the preset's), at
    ``distances`` [m] (default 12 from a tenth of the FEC range to twice it)."""
    from ledsim.radiometry.link_presets import link_constants, preset_named, water_of

    preset = preset_named(name)
    bit_rate = preset.bit_rate if bit_rate is None else bit_rate
    c = link_constants(name, None, water, attenuation)
    w = water_of(preset, water, attenuation)
    if preset.physical:
        w = w.at_wavelength(preset.transmitter.wavelength)
    water_name, beam = w.name, w.attenuation
    if not preset.physical and water is None and attenuation is None:
        water_name, beam = "the bench's", c.attenuation  # the paper's own b, 0.15/m
    reach = range_at_fec(c, bit_rate)
    if distances is None:
        distances = np.geomspace(0.1 * reach, 2.0 * reach, 12)
    rows = [budget_at(c.with_(distance=float(d)), float(d), bit_rate, pointing_error)
            for d in distances]
    return BudgetReport(preset.name, water_name, c.attenuation, beam, bit_rate, FEC_LIMIT,
                        pointing_error, reach, rows)


def format_budget(r: BudgetReport) -> str:
    """The report as a Markdown table with its range at the FEC limit."""
    lines = [f"link {r.link} in {r.water} water (attenuation {r.attenuation_per_m:.3g}/m, "
             f"beam attenuation c {r.beam_attenuation_per_m:.3g}/m), {r.bit_rate:.4g} bit/s "
             f"OOK, pointing error {r.pointing_error_rad:g} rad",
             "",
             "| distance [m] | received power [W] | SNR [dB] | BER | throughput [bit/s] "
             "| FEC share |",
             "|---|---|---|---|---|---|"]
    for row in r.rows:
        snr_db = "-" if row.snr_db is None else f"{row.snr_db:.1f}"
        lines.append(f"| {row.distance_m:.3g} | {row.received_power_w:.3e} | {snr_db} | "
                     f"{row.ber:.2e} | {row.throughput_bps:.4g} | {row.fec_share:.3f} |")
    lines += ["", f"range at the FEC limit (BER {r.fec_limit:g}): "
              f"{r.range_at_fec_limit_m:.3g} m"]
    return "\n".join(lines)


def plot_budget(r: BudgetReport, path) -> None:
    """SNR and BER against distance, the FEC limit and its range marked (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = [row.distance_m for row in r.rows]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True)
    a1.plot(d, [np.nan if row.snr_db is None else row.snr_db for row in r.rows], "o-")
    a1.set_ylabel("SNR [dB]")
    a1.set_title(f"{r.link}, {r.water}, {r.bit_rate:.3g} bit/s")
    a2.semilogy(d, [max(row.ber, 1e-16) for row in r.rows], "o-")
    a2.axhline(r.fec_limit, color="k", ls="--", lw=0.8, label=f"FEC limit {r.fec_limit:g}")
    for ax in (a1, a2):
        ax.axvline(r.range_at_fec_limit_m, color="r", ls=":", lw=0.8)
        ax.grid(True, alpha=0.3)
    a2.set_xlabel("distance [m]")
    a2.set_ylabel("BER")
    a2.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)
