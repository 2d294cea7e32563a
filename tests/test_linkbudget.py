"""The link budget: OOK's bit error rate in Gaussian noise, and the keys a run writes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import run_cli

from ledsim.radiometry.data_channel import BIT_RATE, FEC_LIMIT, ber_ook, link_budget, snr


def test_ook_ber_is_q_of_half_the_amplitude_over_sigma():
    assert ber_ook(0.0) == pytest.approx(0.5)  # no light: a coin toss
    # An SNR of 90: amplitude sqrt(90) = 9.49 sigma, BER Q(4.74) = 1.05e-6
    expected = 0.5 * math.erfc(math.sqrt(90.0) / 2 / math.sqrt(2))
    assert ber_ook(90.0) == pytest.approx(expected, rel=1e-12)
    assert 1.0e-6 < ber_ook(90.0) < 1.1e-6
    # Monte Carlo: threshold at half the amplitude, equiprobable bits, Gaussian noise.
    rng = np.random.default_rng(0)
    amp, sigma = 1.0, 0.3
    bits = rng.integers(0, 2, 400_000)
    rx = bits * amp + rng.normal(0, sigma, bits.size)
    measured = np.mean((rx > amp / 2) != bits)
    assert measured == pytest.approx(ber_ook((amp / sigma) ** 2), rel=0.02)


def test_the_noise_spreads_over_the_bit_rate():
    # sigma over one 50 Hz sample, spread over R_b / 2: the SNR falls as 1 / R_b.
    s1 = snr(1.0, 0.0316, 0.01, 1e3)
    assert s1 == pytest.approx(1 / (0.0316**2 * 10))
    assert snr(1.0, 0.0316, 0.01, 2e3) == pytest.approx(s1 / 2)
    assert snr(-0.1, 0.0316, 0.01) == 0.0  # no negative light


def test_a_run_budget_counts_the_steps_under_the_fec_limit():
    power = np.r_[np.full(80, 1.0), np.zeros(20)]  # aligned, then occluded
    b = link_budget(power, 0.0316, 0.01)
    assert b.fec_share == pytest.approx(0.8) and b.throughput_bps == pytest.approx(800.0)
    assert b.ber == pytest.approx(0.2 * 0.5 + 0.8 * float(ber_ook(snr(1.0, 0.0316, 0.01))))
    assert b.snr_db == pytest.approx(10 * math.log10(0.8 * snr(1.0, 0.0316, 0.01)))
    assert link_budget(np.zeros(10), 0.0316, 0.01).snr_db is None
    # the limit: the power at which the BER crosses 3.8e-3
    p = np.linspace(0.3, 0.8, 501)
    crossing = p[np.argmax(ber_ook(snr(p, 0.0316, 0.01)) < FEC_LIMIT)]
    assert crossing == pytest.approx(0.53, abs=0.01)


@pytest.mark.parametrize("link", ["paper", None])
def test_ledsim_run_writes_the_link_budget(tmp_path, link):
    """On the bench (1 kbit/s) and on the default physical link (its preset's rate)."""
    from ledsim.radiometry.link_presets import DEFAULT_LINK, LINK_PRESETS

    flags = [] if link is None else ["--link", link]
    r = run_cli("run", "--seeds", "2", "--seconds", "6", "--workers", "1", "--no-plot",
                "-q", *flags, "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    for key in ("snr_db", "ber", "throughput_bps", "fec_share", "received_power_w"):
        assert set(res[key]) == {"mean", "std", "n"} and res[key]["n"] == 2, key
    rate = BIT_RATE if link == "paper" else LINK_PRESETS[DEFAULT_LINK].bit_rate
    assert res["bit_rate"] == rate and res["link"] == (link or DEFAULT_LINK)
    assert res["schema_version"] == 3
    assert res["received_power_w"] == res["mean_power"]
    assert 0 < res["fec_share"]["mean"] <= 1
    assert res["throughput_bps"]["mean"] == pytest.approx(rate * res["fec_share"]["mean"])
    assert "FEC share" in r.stdout
