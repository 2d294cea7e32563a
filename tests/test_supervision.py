"""Link supervision: loss detection, the two-photodiode shape invariant, gain tracking,
and reacquisition in the MuJoCo loop (issue: the KKL keeps the link in the real world)."""

import json

import numpy as np
import pytest
from conftest import run_cli

from ledsim.agent.acquisition import fit_incidence_angle
from ledsim.constants import LinkConstants
from ledsim.errors import LedsimError
from ledsim.loop.run_config import RunConfig
from ledsim.loop.run_metrics import link_events
from ledsim.paper.model import LEDLinkModel
from ledsim.radiometry.optics import _SHAPE_PHI, _shape_table, pair_power, pair_shape_inverse
from observer.supervision.gain_tracking import GainTracker
from observer.supervision.monitor import ResidualMonitor

C = LinkConstants()


def test_shape_log_ratio_is_monotonic_so_the_inversion_is_unique():
    assert np.all(np.diff(_shape_table(C.receiver, C.dphi)) > 0)
    assert _SHAPE_PHI[0] < -1.0 and _SHAPE_PHI[-1] > 1.0


@pytest.mark.parametrize("gain", [0.05, 1.0, 3.0])
def test_shape_inverse_recovers_phi_and_gain_whatever_the_gain(gain):
    for phi in np.linspace(-0.8, 0.8, 17):
        p, g, v = pair_shape_inverse(pair_power(gain, phi, C), C)
        assert p == pytest.approx(phi, abs=1e-3)
        assert g == pytest.approx(gain, rel=1e-3)
        assert v > 0
    assert np.isnan(pair_shape_inverse([0.0, 0.3], C)[0])


def test_gain_is_better_determined_at_the_peak_than_off_it():
    v_peak = pair_shape_inverse(pair_power(1.0, 0.0, C), C)[2]
    v_off = pair_shape_inverse(pair_power(1.0, 0.4, C), C)[2]
    assert v_off > 10 * v_peak


def test_scan_fit_finds_phi_now_from_moving_samples_at_unknown_gain():
    rng = np.random.default_rng(0)
    shift = np.linspace(0.08, 0.0, 20)  # phi was larger earlier in the window
    powers = pair_power(0.2, -0.25 + shift, C) + 0.005 * rng.standard_normal((20, 2))
    fit = fit_incidence_angle(powers, shift, C, noise_std=0.005)
    assert fit.phi == pytest.approx(-0.25, abs=0.02)
    assert fit.gain == pytest.approx(0.2, rel=0.05)
    assert fit.chi2 < 3


@pytest.fixture(scope="module")
def model():
    return LEDLinkModel(C)


def _monitor_run(model, x_true, x_hat, steps, seed=0):
    rng = np.random.default_rng(seed)
    mon = ResidualMonitor(model)
    flags = []
    for _ in range(steps):
        y = model.h(x_true) + model.measurement_noise_std * rng.standard_normal(2)
        flags.append(mon.update(y, x_hat))
    return np.array(flags), mon


def test_monitor_stays_quiet_when_the_estimate_is_right(model):
    for phi in (-0.3, 0.0, 0.3):
        x = np.array([phi, 0.0])
        flags, _ = _monitor_run(model, x, x, 3000)
        assert not flags.any()


def test_monitor_flags_a_confident_wrong_estimate_within_0_2_s(model):
    # The case: truth at -0.8 rad (outside the domain), estimate +0.45 rad.
    flags, mon = _monitor_run(model, np.array([-0.8, 0.0]), np.array([0.45, 0.0]), 100)
    first = int(np.argmax(flags))
    assert flags.any() and first * model.Te <= 0.2
    assert flags[first:].all()
    assert "residual" in mon.reason


def test_monitor_flags_an_estimate_outside_the_domain_at_once(model):
    flags, mon = _monitor_run(model, np.array([0.0, 0.0]), np.array([0.9, 0.0]), 1)
    assert flags[0] and "domain" in mon.reason


def test_monitor_learns_the_noise_level(model):
    rng = np.random.default_rng(1)
    mon = ResidualMonitor(model)
    x = np.array([0.0, 0.0])
    for _ in range(2000):
        mon.update(model.h(x) + 3 * model.measurement_noise_std * rng.standard_normal(2), x)
    assert np.allclose(mon.noise_std, 3 * model.measurement_noise_std, rtol=0.2)
    assert not mon.lost


def _tracker(model):
    return GainTracker(model, lambda y: pair_shape_inverse(y, C), model_gain=1.0)


def test_gain_tracker_holds_still_while_the_gain_holds(model):
    rng = np.random.default_rng(2)
    tr = _tracker(model)
    tr.model_gain = float(pair_shape_inverse(model.h(np.array([0.0, 0.0])), C)[1])
    ratios = []
    for _ in range(3000):
        tr.update(model.h(np.array([0.02, 0.0])) + 0.03 * rng.standard_normal(2))
        ratios.append(tr.ratio)
    # The dead band keeps the filter's jitter from the estimator: 30 s within 1%.
    assert np.max(np.abs(np.array(ratios) - 1.0)) < 0.01


def test_gain_tracker_follows_a_halved_gain(model):
    rng = np.random.default_rng(3)
    tr = _tracker(model)
    tr.model_gain = float(pair_shape_inverse(model.h(np.array([0.0, 0.0])), C)[1])
    for _ in range(300):  # 3 s near the peak at half the light
        tr.update(0.5 * model.h(np.array([0.02, 0.0])) + 0.03 * rng.standard_normal(2))
    assert tr.ratio == pytest.approx(0.5, rel=0.05)


def test_link_events_are_the_lost_intervals():
    lost = np.array([0, 1, 1, 0, 0, 1], dtype=bool)
    assert link_events(lost, 0.5) == [[0.5, 1.5], [2.5, None]]


# -- the MuJoCo loop -------------------------------------------------------------------


def _run(**kw):
    from ledsim.loop.closed_loop import run_once

    return run_once(RunConfig(**kw), 0, keep_trace=True)


@pytest.mark.parametrize("estimator", ["kkl", "ekf"])
def test_kick_is_detected_within_0_2_s_and_the_link_is_reacquired(estimator):
    out = _run(estimator=estimator, disturbances=("kick:start=2.5",), seconds=7.0)
    m = out.metrics
    assert m.detection_delay is not None and m.detection_delay <= 0.2
    assert out.trace.acquiring.any()  # the scan ran and found the beam:
    assert m.link_events[-1][1] is not None  # the run ends trusted
    if estimator == "kkl":
        # Aligned again within 1 deg (the EKF holds a ~0.02 rad bias while the hull,
        # spun by the kick's reaction, keeps turning; see docs/disturbances.md).
        assert m.recovery_time is not None


def test_without_supervision_the_kkl_never_recovers_from_a_kick():
    # 12 rad/s: at the default 8 rad/s one seed in four (seed 0) drifts back onto the
    # beam by chance 2.8 s later, the others stay lost.
    out = _run(estimator="kkl", disturbances=("kick:start=2.5,rate=12",), seconds=7.0,
               supervision=False)
    assert out.metrics.recovery_time is None
    assert out.trace.lost is not None and not out.trace.lost.any()


def test_kkl_recovers_after_a_2_s_occlusion():
    out = _run(estimator="kkl", disturbances=("occlusion:start=3,duration=2",), seconds=9)
    assert out.metrics.recovery_time is not None


def test_one_kkl_serves_a_distance_without_a_checkpoint_of_its_own():
    out = _run(estimator="kkl", distance=0.15)
    assert out.metrics.availability > 0.75


def test_the_bank_holds_a_far_link_with_its_noisier_member():
    # One nominal observer kept 0.73 of the power at d = 0.2 m (docs/supervision.md).
    from ledsim.loop.closed_loop import ClosedLoop

    loop = ClosedLoop(RunConfig(estimator="kkl-bank", distance=0.2), 0)
    out = loop.run()[0]
    assert out.metrics.availability > 0.8
    bank = loop.runs[0].step.estimator
    assert bank.noise_ratios[bank.active] == 6.0


def test_cli_run_writes_loss_and_recovery_times(tmp_path):
    r = run_cli("run", "--gimbal", "yaw",
                "--disturbance", "kick:start=2.5", "--seconds", "6", "--seeds", "1",
                "--workers", "1", "--no-plot", "-q", "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    events = res["link_events"][0]["lost_recovered"]
    assert any(a >= 2.5 for a, _ in events)
    assert res["detection_delay"]["n"] == 1 and res["detection_delay"]["mean"] <= 0.2
    assert res["recovery_time"]["n"] == 1
    assert 0 < res["lost_share"]["mean"] < 1 and res["supervision"] is True


def test_detection_delay_counts_a_loss_already_on_at_the_event():
    from ledsim.loop.run_metrics import run_metrics

    n = 400
    x = np.zeros((n, 2))
    lost = np.zeros(n, dtype=bool)
    lost[290:350] = True  # flagged at 2.9 s, before the event at 3 s
    m = run_metrics(x, x, np.ones((n, 2)), 1.0, C, event_end=3.5, lost=lost,
                    event_start=3.0)
    assert m.detection_delay == 0.0
    lost[:] = False
    lost[312:330] = True
    m = run_metrics(x, x, np.ones((n, 2)), 1.0, C, event_end=3.5, lost=lost,
                    event_start=3.0)
    assert m.detection_delay == pytest.approx(0.12)


def test_converging_from_the_initial_guess_is_not_a_lost_link():
    # The KKL's first 0.4 s used to show as a loss ([[0.06, 0.43]]) with no disturbance.
    out = _run(estimator="kkl", acquisition="warm-up")
    assert out.metrics.link_events == []
    assert not out.trace.lost.any()
    # The minimum-time start says it has no link until it has one: one event from the
    # start to the hand-over, and none after it.
    fast = _run(estimator="kkl")
    (start, end), = fast.metrics.link_events
    assert start == 0.0 and end is not None and end < 0.25
    assert not fast.trace.lost[int(round(end / 0.01)):].any()


def test_a_fast_kick_is_flagged_at_once_and_recovered():
    # 12 rad/s spins the receiver off the beam: the gate holds the dark samples as a
    # dropout, but the encoder travels while blind, which no occlusion does (it was
    # flagged after 0.7-1.9 s, and half the seeds never came back).
    out = _run(estimator="kkl", disturbances=("kick:start=6,rate=12",), seconds=10.0)
    events = out.metrics.link_events
    assert out.metrics.detection_delay is not None and out.metrics.detection_delay <= 0.2
    assert events and events[0][1] is not None  # recovered
    assert out.metrics.recovery_time is not None


def test_the_gate_holds_a_dropout_then_passes_a_blackout_on():
    from ledsim.agent.gate import DropoutGate

    gate = DropoutGate(C, max_hold=0.5)  # 50 steps of 10 ms
    lit, dark = np.array([1.0, 0.9]), np.array([0.0, 0.0])
    for _ in range(20):
        gate(lit)
    out = np.array([gate(dark) for _ in range(200)])
    assert np.isnan(out[:50]).all()  # a dropout: held
    assert np.isfinite(out[50:]).all()  # then every dark sample passes (not 1 a second)
    assert np.isfinite(gate(lit)).all()  # light returns
    for _ in range(20):
        gate(lit)
    assert np.isnan(gate(dark)).all()  # and a new darkness, once lit again, is a dropout
    forever = DropoutGate(C, max_hold=float("inf"))
    for _ in range(20):
        forever(lit)
    assert np.isnan([forever(dark) for _ in range(500)]).all()


def test_the_monitor_sees_no_light_but_a_weak_steady_link_as_light(model):
    rng = np.random.default_rng(2)
    sigma = model.measurement_noise_std
    mon = ResidualMonitor(model)
    dark = [mon._no_light(list(sigma * rng.standard_normal(2)), [True, True])
            for _ in range(mon.dark_steps)]
    assert dark[-1] and not any(dark[:-1])  # after dark_time (0.2 s) of darkness
    # A weak but steady link, two noise levels bright at its brighter photodiode.
    weak = ResidualMonitor(model)
    y = model.h(np.zeros(2))
    y = y * (2 * sigma / y.max())
    seen = [weak._no_light(list(y + sigma * rng.standard_normal(2)), [True, True])
            for _ in range(500)]
    assert not any(seen)


def test_filters_with_the_kkls_knowledge_of_the_distance_hold_a_far_link():
    # --filter-distance nominal: the 0.085 m model and the supervisor's gain tracker.
    out = _run(estimator="ekf", distance=0.2, filter_distance="nominal")
    assert out.metrics.availability > 0.8 and out.metrics.rmse_steady["x1"] < 0.02
    with pytest.raises(LedsimError, match="--filter-distance nominal"):
        RunConfig(estimator="ekf", filter_distance="nominal", supervision=False).validate()
    with pytest.raises(LedsimError, match="filter-distance"):
        RunConfig(filter_distance="guess").validate()


def test_the_scheduled_kkl_is_told_the_noise_of_a_far_link():
    # At d = 0.2 m the powers, rescaled to the reference gain, carry about 5.6x the
    # nominal noise: the gain-scheduled KKL averages longer than on a near link.
    from ledsim.loop.closed_loop import ClosedLoop

    loop = ClosedLoop(RunConfig(estimator="kkl", distance=0.2), 0)
    out = loop.run()[0]
    assert out.metrics.availability > 0.65
    est = loop.runs[0].step.estimator
    assert 4.0 < est.noise < 8.0
    assert est.w < est.schedule.floor(1.0)


def test_a_confident_wrong_estimate_is_counted_as_a_silent_error():
    from ledsim.constants import LinkConstants
    from ledsim.loop.run_metrics import run_metrics

    c = LinkConstants()
    n = 400  # 4 s
    x = np.zeros((n, 2))
    xhat = np.zeros((n, 2))
    xhat[100:200, 0] = 0.3  # 1 s off by 0.3 rad, flag down
    xhat[250:300, 0] = 0.5  # 0.5 s off, flagged lost: not silent
    lost = np.zeros(n, bool)
    lost[250:300] = True
    power = np.ones((n, 2))
    m = run_metrics(x, xhat, power, 1.0, c, lost=lost, warmup=1.0)
    assert m.silent_error_share == pytest.approx(100 / 300)
    assert run_metrics(x, xhat, power, 1.0, c, lost=lost, warmup=2.0).silent_error_share == 0
    assert run_metrics(x, xhat, power, 1.0, c).silent_error_share == pytest.approx(150 / 400)
