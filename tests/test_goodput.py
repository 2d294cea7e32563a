"""Goodput (issue 49): the data a run delivers through the link's FEC code while its
supervisor holds the link, against the same path pointed perfectly."""

import csv
import json

import numpy as np
import pytest
from conftest import run_cli

from ledsim.loop.closed_loop import run_once
from ledsim.loop.run_config import RunConfig
from ledsim.radiometry.data_channel import FEC_LIMIT
from ledsim.radiometry.goodput import (
    CODE_K,
    CODE_N,
    CODE_T,
    delivered_bits,
    frame_error_rate,
    goodput,
)
from observer.noise import MeasurementNoise


def test_the_codes_frame_error_rate_is_the_binomial_tail_and_waterfalls_at_the_fec_limit():
    rng = np.random.default_rng(0)
    for p in (4.2e-3, 4.5e-3, 5e-3):
        errors = rng.binomial(CODE_N, p, size=200_000)
        sampled = np.mean(errors > CODE_T)
        exact = float(frame_error_rate(p))
        assert abs(sampled - exact) < 4 * np.sqrt(exact * (1 - exact) / errors.size) + 1e-4
    fer = frame_error_rate([0.0, 1e-4, FEC_LIMIT, 6e-3, 0.5])
    assert fer[0] == 0.0 and fer[1] < 1e-9 and fer[2] < 2e-3 and fer[3] > 0.99
    assert fer[4] == 1.0 and np.all(np.diff(frame_error_rate(np.linspace(0, 0.01, 50))) >= 0)


def test_goodput_counts_held_steps_and_an_outage_by_its_length():
    noise, Te, rate = MeasurementNoise(1e-11), 0.01, 1e5
    power = np.full(300, 1e-7)  # SNR 1e5: every frame decodes
    best = power * 1.01
    held = np.ones(300, bool)
    held[:10] = False  # the opening acquisition: lost bits, no outage
    held[100:130] = False  # a loss of 0.3 s
    g = goodput(power, best, noise, Te, rate, held, np.linspace(30.0, 20.0, 300))
    per_step = rate * Te * CODE_K / CODE_N
    assert delivered_bits(power, noise, Te, rate) == pytest.approx(per_step)
    assert g.goodput_bits == pytest.approx(260 * per_step)
    assert g.ideal_bits == pytest.approx(300 * per_step)
    assert (g.outages, g.outage_s) == (1, pytest.approx(0.3))
    assert g.range_m == [20.0, 30.0]


def test_an_occlusion_costs_its_bits_and_is_one_outage():
    cfg = RunConfig(link="luma", seconds=6.0, disturbances=("occlusion:start=3,duration=1",))
    m = run_once(cfg, 0).metrics
    clear = run_once(RunConfig(link="luma", seconds=6.0), 0).metrics
    per_s = cfg.data_bit_rate * CODE_K / CODE_N
    assert clear.goodput_bits <= clear.ideal_bits and clear.outages == 0
    assert m.outages == 1 and 1.0 <= m.outage_s <= 1.3, m
    assert clear.goodput_bits - m.goodput_bits == pytest.approx(m.outage_s * per_s,
                                                                rel=0.05)


def test_results_json_and_the_sweeps_csv_give_the_data_delivered(tmp_path):
    r = run_cli("run", "--seconds", "2", "--seeds", "2", "--no-plot", "-q", "--out",
                str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    assert 0 < res["goodput_bits"]["mean"] <= res["ideal_bits"]["mean"]
    assert res["outages"]["mean"] == 0 and res["outage_s"]["mean"] == 0
    assert 29.9 < res["range_m"][0] <= res["range_m"][1] < 30.1
    r = run_cli("sweep", "--seeds", "1", "--seconds", "1", "--estimator", "ekf",
                "--workers", "1", "--no-plot", "-q", "--out", str(tmp_path / "s"))
    assert r.returncode == 0, r.stderr
    with open(tmp_path / "s" / "results.csv") as f:
        row = next(csv.DictReader(f))
    assert float(row["goodput_bits"]) > 0 and row["outages"] == "0"
    near, far = map(float, row["range_m"].split(";"))
    assert near <= far


def test_the_tails_that_underflow_are_skipped_to_the_full_sums_bits():
    """A clean step's tail is 0.0 without its 800 terms: the same bits as summing them."""
    from ledsim.radiometry import goodput as g

    ber = np.concatenate([[0.0, 1e-300], np.geomspace(1e-30, 0.5, 4000),
                          np.random.default_rng(0).uniform(0.0, 0.01, 2000)])
    p = np.clip(ber, 0.0, 0.5)
    small = (p > 0) & (p * g.CODE_N < g.CODE_T)
    large = p * g.CODE_N >= g.CODE_T
    full = np.zeros(p.shape)
    full[small] = g._sum_exp(g._log_terms(g._ABOVE, g._CHOOSE_ABOVE, p[small][:, None]))
    full[large] = 1.0 - g._sum_exp(g._log_terms(g._BELOW, g._CHOOSE_BELOW, p[large][:, None]))
    fer = g.frame_error_rate(ber)
    assert np.array_equal(fer, np.clip(full, 0.0, 1.0))
    assert 0 < np.count_nonzero(fer[small]) < np.count_nonzero(small)  # both kinds occur
    assert g.frame_error_rate(np.full((2, 3), 0.005)).shape == (2, 3)
