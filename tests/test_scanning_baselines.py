"""The field's one-photodiode pointing baselines (issue 49's benchmark): extremum seeking
and Solanki et al.'s scanning EKF, in closed loop on the head's fitted model, and their
place in the registry and the run's checks."""

import numpy as np
import pytest

from ledsim.agent.laws import AlignmentPID
from ledsim.errors import LedsimError
from ledsim.physics.head_model import HeadModel
from observer.baselines.scanning import DIP, ExtremumSeeking, ScanningEKF, dip_radius
from tests.test_two_axis_tracking import quad_world


@pytest.fixture(scope="module")
def model():
    return HeadModel.fit(quad_world())


def closed_loop(model, est, x0, seconds: float, noise: float = 0.0, seed: int = 0,
                garbage: bool = False):
    """The model's head driven by the alignment law on ``est``'s reports, from the
    truth ``x0`` with the estimator started at the boresight: the truth's angles per
    step, and the estimator's belief."""
    ref = model.constants.layout.reference
    rng = np.random.default_rng(seed)
    law = AlignmentPID(phi_ref=0.0, Te=model.Te)
    x, truth, beliefs = np.array(x0, dtype=float), [], []
    est.reset(np.zeros(4))
    for _ in range(int(round(seconds / model.Te))):
        y = model.h(x) * (1 + noise * rng.standard_normal(model.n_output))
        if garbage:  # what the other photodiodes read must not matter
            keep = y[ref]
            y = rng.uniform(-1, 1, y.size)
            y[ref] = keep
        rep = est.update(y)
        u = law(rep, 0.0)
        est.predict(u)
        x = model.f(x, u)
        truth.append(x[:2].copy())
        beliefs.append(est.belief)
    return np.array(truth), np.array(beliefs)


def test_the_scan_circles_where_the_beam_gives_up_its_dip(model):
    ref = model.constants.layout.reference
    a = dip_radius(model, ref)
    peak = model.h(np.zeros(4))[ref]
    assert model.h(np.array([a, 0, 0, 0]))[ref] == pytest.approx((1 - DIP) * peak, rel=1e-6)
    est = ScanningEKF(model, ref)
    est.reset(np.zeros(4))
    offsets = []
    for _ in range(int(round(2.0 / model.Te))):
        offsets.append(est.update(model.h(np.zeros(4)))[:2] - est.belief[:2])
        est.predict(np.zeros(2))
    r = np.linalg.norm(offsets, axis=1)
    np.testing.assert_allclose(r, a, rtol=1e-9)  # a circle of the dip's radius
    assert np.ptp(np.array(offsets)[:, 0]) == pytest.approx(2 * a, rel=1e-3)


@pytest.mark.parametrize("kind", [ExtremumSeeking, ScanningEKF])
def test_each_climbs_to_the_led_from_an_offset_it_does_not_know(model, kind):
    # The truth starts 0.06 rad off on both axes; the estimator believes the boresight.
    ref = model.constants.layout.reference
    truth, _ = closed_loop(model, kind(model, ref), [0.06, -0.05, 0, 0], 40.0, noise=1e-3)
    a = dip_radius(model, ref)
    last = truth[-int(round(4.0 / model.Te)):]  # the last two scan periods
    centre = last.mean(axis=0)
    assert np.linalg.norm(centre) < 0.2 * a, centre  # the scan is centred on the LED
    assert np.linalg.norm(truth[0]) > 0.07  # it started off


def test_extremum_seeking_never_evaluates_the_power_model(model):
    ref = model.constants.layout.reference
    est = ExtremumSeeking(model, ref)

    class NoH:  # f and Te only: the hill climb is model-free
        Te, n_state = model.Te, 4
        domain_center = model.domain_center
        f = staticmethod(model.f)

        def h(self, x):
            raise AssertionError("extremum seeking evaluated h")

    est.system = NoH()
    truth, _ = closed_loop(model, est, [0.04, 0.03, 0, 0], 30.0)
    assert np.linalg.norm(truth[-int(round(2.0 / model.Te)):].mean(axis=0)) < 0.02


def test_the_scanning_ekf_reads_only_the_data_detector(model):
    ref = model.constants.layout.reference
    a = closed_loop(model, ScanningEKF(model, ref), [0.05, 0.02, 0, 0], 3.0, seed=3)
    b = closed_loop(model, ScanningEKF(model, ref), [0.05, 0.02, 0, 0], 3.0, seed=3,
                    garbage=True)
    np.testing.assert_array_equal(a[1], b[1])


def test_they_run_only_on_the_pan_tilt_head():
    from ledsim.loop.run_config import RunSpec

    for name in ("es", "scan-ekf"):
        with pytest.raises(LedsimError, match=f"estimator '{name}' runs on the pan-tilt "
                                              "head only"):
            RunSpec(estimator=name).validate()
        with pytest.raises(LedsimError, match="pan-tilt head only"):
            RunSpec(estimator=name, link="luma", gimbal="yaw").validate()
        RunSpec(estimator=name, link="luma").validate()  # a physical link's default head
        RunSpec(estimator=name, link="luma", scenario="flyby").validate()


def test_a_station_run_with_a_baseline_scans_and_keeps_the_link():
    """End to end in MuJoCo: the scan costs about its dip, and the link stands."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunSpec

    out = run_once(RunSpec(estimator="es", link="luma", seconds=8.0), 0)
    m = out.metrics
    assert m.availability > 0.95
    assert 0.03 < m.pointing_loss_db < 0.3  # the 2 % dip is 0.09 dB
