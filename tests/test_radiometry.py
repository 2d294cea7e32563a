"""The physical link: water, hardware, noise, presets and the budget."""

import json
import math

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.constants import LinkConstants
from ledsim.radiometry.budget import budget_report, range_at_fec
from ledsim.radiometry.data_channel import (
    FEC_LIMIT,
    ber_ook,
    link_budget,
    link_budget_of,
    snr,
    snr_at,
)
from ledsim.radiometry.hardware import ELEMENTARY_CHARGE
from ledsim.radiometry.link import constants_from_dict
from ledsim.radiometry.link_presets import LINK_PRESETS, link_constants
from ledsim.radiometry.optics import photodiode_power
from ledsim.radiometry.water import WATER_TYPES, Water, pure_water_absorption
from observer.noise import Digitiser, MeasurementNoise


def test_paper_preset_is_the_paper_constants():
    c = link_constants("paper")
    assert c == LinkConstants()
    assert "link" not in c.to_dict()  # checkpoints' metadata keeps its keys
    assert not c.measurement_noise().signal_dependent
    assert link_constants("paper", 0.2) == LinkConstants(distance=0.2)
    assert link_constants("paper", water="harbour").attenuation == pytest.approx(2.19)


def test_physical_constants_round_trip_through_metadata():
    c = link_constants("luma", 12.0, "coastal")
    back = constants_from_dict(json.loads(json.dumps(c.to_dict())))
    assert back == c
    assert back.measurement_noise() == c.measurement_noise()
    assert constants_from_dict(LinkConstants().to_dict()) == LinkConstants()


def _hg_share(g, half_angle, n=200_001):
    """Henyey-Greenstein share within ``half_angle``, by numeric integration."""
    mu = np.linspace(math.cos(half_angle), 1.0, n)
    p = (1 - g * g) / (2 * (1 + g * g - 2 * g * mu) ** 1.5)
    return float(np.sum((p[1:] + p[:-1]) / 2 * np.diff(mu)))


def test_received_power_against_a_hand_computation():
    """LUMA at 30 m in clear ocean, aligned, worked out here from the published numbers."""
    d = 30.0
    # Water at 450 nm: pure water's absorption swapped (Pope and Fry: 0.0507 at 530 nm,
    # 0.00922 at 450 nm), b times 530/450.
    a = 0.114 - 0.0507 + 0.00922
    b = 0.037 * 530 / 450
    half = math.radians(30.0)  # the beam and the field of view are both 30 deg
    k = a + b * (1 - _hg_share(0.924, half))
    m = -math.log(2) / math.log(math.cos(half))
    intensity = 3.5 * (m + 1) / (2 * math.pi)  # W/sr
    area = math.pi * 0.005**2  # the APD's 10 mm diameter, m^2
    hand = intensity * area * 0.9 * math.exp(-k * d) / d**2
    c = link_constants("luma", d)
    assert c.attenuation == pytest.approx(k, rel=1e-6)
    assert float(photodiode_power(d, 0.0, 0.0, c)) == pytest.approx(hand, rel=1e-6)


def test_water_model():
    w = WATER_TYPES["coastal"]
    assert w.attenuation == pytest.approx(0.398)
    assert w.forward_share(math.pi) == pytest.approx(1.0)
    assert w.forward_share(0.0) == pytest.approx(0.0, abs=1e-12)
    assert w.forward_share(0.3) == pytest.approx(_hg_share(0.924, 0.3), rel=1e-6)
    assert w.absorption < w.effective_attenuation(0.3) < w.attenuation
    assert w.effective_attenuation(0.0) == pytest.approx(w.attenuation)
    assert w.diffuse_attenuation() == pytest.approx(math.sqrt(0.179**2 + 0.256 * 0.179
                                                              * 0.219))
    assert w.at_wavelength(530.0) == w
    assert pure_water_absorption(450.0) == pytest.approx(0.00922)
    v = Water.from_visibility(3.0, WATER_TYPES["harbour"])
    assert v.attenuation == pytest.approx(1.6)
    assert v.albedo == pytest.approx(WATER_TYPES["harbour"].albedo)


def test_noise_terms_and_digitiser():
    n = MeasurementNoise(1e-9, 2, 1.0, shot_coefficient=1e-12)
    p = np.array([0.0, 1e-6])
    assert n.analog_std(p) == pytest.approx(np.sqrt(1e-18 + 1e-12 * p))
    dig = Digitiser(12, 1e-3, 6, step_ratio=10.0)
    # the most sensitive range that holds twice the signal, a decade apart
    assert dig.range_of(np.array([4e-4, 6e-4, 4e-5, 1e-12])) == pytest.approx(
        [1e-3, 1e-3, 1e-4, 1e-9])  # six decades below full scale
    six_db = Digitiser(12, 1e-3, 6)  # 6 dB steps: the signal within a factor 2 of range
    clean = np.geomspace(1e-9, 4e-4, 50)
    top = six_db.range_of(clean)
    assert np.all((top >= 2 * clean) & (top < 4 * clean * (1 + 1e-9)))
    assert six_db.n_ranges == 21
    assert dig.apply(np.array([5e-3]), np.array([6e-4]))[0] == pytest.approx(1e-3)  # clips
    steps = dig.apply(np.array([1.23456e-5]), np.array([1.2e-5]))[0] / dig.step(1.2e-5)
    assert steps == pytest.approx(round(steps))
    noisy = MeasurementNoise(1e-9, 2, 1.0, 1e-12, dig)
    clean = np.full((40_000, 2), 2e-7)
    draws = noisy.measure(clean, np.random.default_rng(0)) - clean
    assert np.std(draws) == pytest.approx(noisy.std_at(clean[0])[0], rel=0.03)
    # averaged conversions: dithered by the analog noise, unbiased, and the quantisation
    # shrinks with their number; too little noise to dither: the rounding stays
    averaged = MeasurementNoise(2e-10, 2, 1.0, 0.0, Digitiser(12, 1e-3, 6, conversions=10_000))
    clean = np.full((40_000, 2), 2.1e-7)
    step = averaged.digitiser.step(2.1e-7)
    assert averaged.digitiser.dithered(averaged.analog_std(2.1e-7), 2.1e-7)
    draws = averaged.measure(clean, np.random.default_rng(1)) - clean
    assert abs(np.mean(draws)) < 3 * 2e-10 / math.sqrt(draws.size)
    assert np.std(draws) == pytest.approx(math.sqrt(4e-20 + step**2 / 12 / 10_000), rel=0.03)
    quiet = MeasurementNoise(1e-15, 2, 1.0, 0.0, Digitiser(12, 1e-3, 6, conversions=10_000))
    assert not quiet.digitiser.dithered(quiet.analog_std(2.1e-7), 2.1e-7)
    assert quiet.std_at(np.array([2.1e-7]))[0] == pytest.approx(step / math.sqrt(12), rel=1e-3)
    # the paper's noise ignores the signal and draws as before
    paper = LinkConstants().measurement_noise()
    assert paper.std_at(np.array([5.0, 0.1])) == pytest.approx([paper.std] * 2)
    assert not paper.signal_dependent


def test_budget_reduces_to_the_paper_formula():
    c = LinkConstants()
    power = np.linspace(0.0, 1.0, 11)
    noise = c.measurement_noise()
    assert np.array_equal(snr_at(power, noise, c.Te), snr(power, noise.std, c.Te))
    assert link_budget_of(power, noise, c.Te) == link_budget(power, noise.std, c.Te)
    # with shot noise the BER is Q(P / (sigma_on + sigma_off))
    shot = MeasurementNoise(1e-9, 2, 1.0, 1e-14)
    data = shot.at_bandwidth(1e6 * c.Te)
    p = 3e-7
    q = p / (math.sqrt(data.nominal_std**2 + data.shot_coefficient * p) + data.nominal_std)
    assert ber_ook(snr_at(np.array([p]), shot, c.Te, 1e6))[0] == pytest.approx(
        0.5 * math.erfc(q / math.sqrt(2)), rel=1e-9)


def test_range_at_the_fec_limit():
    c = link_constants("luma")
    r = range_at_fec(c, 5e5)
    p_at = float(photodiode_power(r, 0.0, 0.0, c))
    ber = ber_ook(snr_at(np.array([p_at]), c.measurement_noise(), c.Te, 5e5))[0]
    assert ber == pytest.approx(FEC_LIMIT, rel=1e-3)
    assert range_at_fec(c, 5e6) < r  # a faster link reaches less far
    assert range_at_fec(link_constants("luma", water="harbour"), 5e5) < r


@pytest.mark.parametrize("name", [n for n, p in LINK_PRESETS.items() if p.physical])
def test_presets_within_a_factor_of_their_published_ranges(name):
    """The issue's target: each computed range within 1.5x of its published figure."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from link_presets import computed_range

    p = LINK_PRESETS[name]
    for f in p.published:
        assert 1 / 1.5 <= computed_range(p, f) / f.range <= 1.5, (name, f)


def test_photon_shot_noise_scale():
    """The shot coefficient is 2 q F B / R: a photodiode's, by hand."""
    det = link_constants("aquaoptical").link.detector
    floor, shot = det.noise_terms(0.0, 50.0)
    assert shot == pytest.approx(2 * ELEMENTARY_CHARGE * 50.0 / det.responsivity)
    assert floor == pytest.approx((2 * ELEMENTARY_CHARGE * det.dark_current
                                   + det.amplifier_noise**2) * 50.0 / det.responsivity**2)


def test_budget_report_and_cli(tmp_path):
    report = budget_report("luma", "clear-ocean", bit_rate=5e5)
    assert report.range_at_fec_limit_m == pytest.approx(range_at_fec(link_constants("luma"),
                                                                      5e5))
    shares = [row.fec_share for row in report.rows]
    assert shares[0] == 1.0 and shares[-1] == 0.0
    r = run_cli("budget", "--link", "luma", "--json", "--plot", str(tmp_path / "b.png"))
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert data["range_at_fec_limit_m"] == pytest.approx(report.range_at_fec_limit_m)
    assert (tmp_path / "b.png").stat().st_size > 1000
    assert_user_error(run_cli("budget", "--link", "luma", "--water", "muddy"), "muddy")
    assert_user_error(run_cli("budget", "--link", "luma", "--attenuation", "-1"),
                      "--attenuation")


def test_a_physical_link_runs_and_a_seed_does_not_depend_on_its_batch():
    """The signal-dependent draw (shot noise and the ADC) in the batch's sensor and the
    single run's: the same numbers for a seed, alone or beside another."""
    from ledsim.loop.closed_loop import run_batch, run_once
    from ledsim.loop.run_config import RunConfig

    cfg = RunConfig(estimator="ekf", link="aquaoptical", water="coastal", distance=15.0,
                    seconds=1.5, seeds=2)
    cfg.validate()
    alone = run_once(cfg, 1, keep_trace=True)
    both = run_batch(cfg, [0, 1], keep_trace=True)
    np.testing.assert_array_equal(alone.trace.power, both[1].trace.power)
    np.testing.assert_array_equal(alone.trace.xhat, both[1].trace.xhat)
    power, clean = alone.trace.power, alone.trace.power_clean
    assert np.all(clean > 0) and np.all(np.isfinite(alone.trace.xhat))
    # the noise is the receiver's at the signal: a few ADC steps, far below the signal
    step = clean / 2**11  # the ADC's step is between this and ten times it
    assert np.all(np.abs(power - clean) < 50 * step)
    assert alone.metrics.fec_share is not None


def test_the_benchs_observers_refuse_a_physical_link(tmp_path):
    """The unsupervised KKL is the bench's: a physical link's KKLs need the supervisor's
    gain tracker."""
    for extra in (["--estimator", "kkl", "--no-supervision"],
                  ["--estimator", "kkl-scheduled", "--no-supervision"]):
        assert_user_error(run_cli("run", "--link", "luma", *extra, "--out",
                                  str(tmp_path / "x")), "no shipped observer")
    assert_user_error(run_cli("run", "--link", "luma", "--estimator", "ekf",
                              "--filter-distance", "nominal", "--out", str(tmp_path / "y")),
                      "--filter-distance nominal")


def test_the_gain_trackers_deadband_follows_the_link():
    from ledsim.agent.link_gain import BENCH_DEADBAND, tracker_deadband

    assert tracker_deadband(LinkConstants()) == BENCH_DEADBAND
    assert tracker_deadband(LinkConstants(distance=0.05)) == BENCH_DEADBAND
    from ledsim.radiometry.optics import nominal_noise_std, peak_power

    bench = LinkConstants().measurement_noise_std / peak_power(LinkConstants())
    for d in (6.0, 10.0, 30.0, 60.0):  # in proportion to the samples' relative noise
        c = link_constants("luma", d)
        relative = nominal_noise_std(c) / peak_power(c)
        assert tracker_deadband(c) == pytest.approx(BENCH_DEADBAND * relative / bench)
        assert 1e-6 < tracker_deadband(c) < BENCH_DEADBAND / 10


def test_the_physical_kkl_runs_on_every_preset():
    """The shipped scheduled KKL of the physical receiver loads for each preset (its
    metadata checked against the reference world) and aligns a short run."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    for name in ("aquaoptical", "bluecomm-200"):
        cfg = RunConfig(estimator="kkl", link=name, seconds=3.0, seeds=1)
        cfg.validate()
        out = run_once(cfg, 0)
        assert out.metrics.rmse_steady["x1"] < 0.02, name
        assert out.metrics.availability > 0.9, name
