"""Two-axis tracking from the photodiodes alone (issue 48): the head's four-state model
fitted to MuJoCo, an EKF in four states on it, and the control step pointing a quad on a
pan-tilt head at the LED on both axes."""

from dataclasses import replace

import numpy as np
import pytest

from ledsim.agent.laws import AlignmentPID
from ledsim.agent.step import ControlStep, GimbalMotor, Unsupervised, identity_gate
from ledsim.physics import head
from ledsim.physics.head_model import HeadModel
from ledsim.physics.layout import AZIMUTH, quad_layout
from ledsim.physics.scene import WorldConfig
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld
from ledsim.physics.world_rows import WorldRows
from ledsim.radiometry.link_presets import link_constants
from observer.baselines.ekf import ExtendedKalmanFilter


def quad_world() -> LinkWorld:
    c = replace(link_constants("luma", 30.0), receiver_layout=quad_layout(0.1))
    return LinkWorld(WorldConfig(constants=c, depth=20.0))


@pytest.fixture(scope="module")
def model():
    return HeadModel.fit(quad_world())


def truth(sensor) -> np.ndarray:
    """The line of sight's azimuth and elevation in the head's frame [rad]: the data
    detector's (on the boresight)."""
    return np.array([sensor.read(noise=False).incidence_angle[0], sensor.elevation()[0]])


def test_the_model_predicts_one_step_of_the_head(model):
    world = quad_world()
    rng = np.random.default_rng(5)
    err = []
    for _ in range(100):
        x, u = rng.uniform(-0.4, 0.4, 4), rng.uniform(-10, 10, 2)
        world.reset(gimbal_angle=-x[:2], gimbal_rate=-x[2:])
        world.set_torques(model.torque_for(u))
        world.step()
        err.append(np.r_[-world.gimbal_angles, -world.gimbal_rates] - model.f(x, u))
    rms = np.sqrt(np.mean(np.square(err), axis=0))
    assert np.all(rms[:2] < 1e-5) and np.all(rms[2:] < 1e-3), rms  # 9e-7, 1e-8; 2e-4, 2e-6
    jac = model.h_jacobian(np.array([0.1, -0.05, 0.0, 0.0]))
    from observer.system import _central_jacobian

    np.testing.assert_allclose(jac, _central_jacobian(model.h, np.array([0.1, -0.05, 0, 0]),
                                                      1e-6), atol=1e-18)


def ekf_error(model, model_error: float | None = None, steps: int = 800,
              kind=ExtendedKalmanFilter) -> np.ndarray:
    """The filter's (an EKF unless told) largest angle errors [rad] past its first
    second, the head driven on both axes by known inputs and starting (0.2, -0.15) rad
    off."""
    world = quad_world()
    world.reset(gimbal_angle=np.array([0.2, -0.15]), gimbal_rate=np.zeros(2))
    sensor = IrradianceSensor(world, seed=1)
    if model_error is not None:
        model = replace_error(model, model_error)
    ekf = kind(model)
    ekf.reset(np.zeros(4))
    worst = np.zeros(2)
    Te = model.Te
    for k in range(steps):
        xhat = ekf.update(sensor.read().power)
        if k * Te >= 1.0:
            worst = np.maximum(worst, np.abs(xhat[:2] - truth(sensor)))
        u = np.array([0.3 * np.sin(1.3 * k * Te), 0.2 * np.cos(0.9 * k * Te)])
        ekf.predict(u)
        world.set_torques(model.torque_for(u))
        world.step()
    return worst


def replace_error(model, error: float):
    import copy

    other = copy.copy(model)
    other.model_error = error
    return other


def test_the_ukf_and_the_pf_in_four_states_follow_both_angles_too(model):
    from observer.baselines.pf import ParticleFilter
    from observer.baselines.ukf import UnscentedKalmanFilter

    for kind in (UnscentedKalmanFilter, ParticleFilter):
        worst = ekf_error(model, kind=kind)
        assert np.all(worst < 0.02), (kind.__name__, worst)  # 8e-3, 4e-3; 7e-3, 7e-3


def test_an_ekf_in_four_states_follows_both_angles(model):
    worst = ekf_error(model)
    assert np.all(worst < 0.02), worst  # 9e-3 and 4e-3 measured
    # At luma's SNR the noise is 5e-5 of the power: trusting h to that, the EKF is
    # thrown off by the model's own 0.3 % (the model_error the filter counts).
    assert np.max(ekf_error(model, model_error=0.0)) > 0.1


def point(model, world) -> tuple[np.ndarray, float]:
    """The control step with the EKF points the quad from 0.25, -0.2 rad off for 4 s;
    the last second's largest pointing error per axis [rad] and the data detector's
    least power over its best then [-]."""
    world.reset(gimbal_angle=np.array([0.25, -0.2]), gimbal_rate=np.zeros(2))
    sensor = IrradianceSensor(world, seed=3)
    c = world.config.constants
    step = ControlStep(identity_gate, Unsupervised(ExtendedKalmanFilter(model)),
                       AlignmentPID(phi_ref=0.0), c,
                       GimbalMotor(model.inertia, limit=world.config.torque_limit),
                       warmup=0.3)
    worst, share = np.zeros(2), 1.0
    with WorldRows([world]) as rows:
        rows.start([sensor], [[]], [None])
        for k in range(400):
            r = sensor.read()
            torque = step(r.power, k * c.Te, world.gimbal_angles, world.gimbal_rates)
            if k >= 300:
                worst = np.maximum(worst, np.abs(truth(sensor)))
                share = min(share, float(r.power_clean[0] / model.power_gain))
            rows.tick((k + 1) * c.Te, torques=[torque])
    return worst, share


def test_the_control_step_points_the_quad_on_both_axes_from_its_powers(model):
    worst, share = point(model, quad_world())
    assert np.all(worst < 0.01), worst  # 1e-4 and 4.4e-3 rad measured
    assert share > 0.99


def test_the_pointing_fails_with_the_tilt_motor_on_the_pan_hinge(model, monkeypatch):
    built = head.add_motor
    monkeypatch.setattr(head, "add_motor",
                        lambda spec, name, joint: built(spec, name, AZIMUTH.joint))
    worst, _ = point(model, quad_world())
    assert worst[1] > 0.05


@pytest.mark.parametrize("start", [(0.3, 0.2), (0.3, -0.2)])
def test_minimum_time_acquisition_on_both_axes_is_within_twice_the_bound(model, start):
    """The issue's acquisition target from (0.3, 0.2) rad off: the slew at the torque
    limit on both hinges (``TimeOptimalSlew`` over two axes, steered by the EKF's
    estimate) arrives within twice the minimum-time bound, the longer of the two
    hinges' bang-bang times 2 sqrt(angle / a), a = limit / I (0.13 s against 0.071 s
    measured, counting the step it arrives in: 1.8x)."""
    import math

    from ledsim.agent.slew import TimeOptimalSlew

    world = quad_world()
    world.reset(gimbal_angle=np.array(start), gimbal_rate=np.zeros(2))
    sensor = IrradianceSensor(world, seed=3)
    c, limit = world.config.constants, world.config.torque_limit
    slew = TimeOptimalSlew(model.inertia, limit, c.Te)
    step = ControlStep(identity_gate,
                       Unsupervised(ExtendedKalmanFilter(model), slew, phi_ref=0.0),
                       AlignmentPID(phi_ref=0.0), c, GimbalMotor(model.inertia, limit=limit))
    bound = max(2 * math.sqrt(abs(q) / (limit / inertia))
                for q, inertia in zip(start, model.inertia, strict=True))
    arrived = None
    with WorldRows([world]) as rows:
        rows.start([sensor], [[]], [None])
        for k in range(200):
            torque = step(sensor.read().power, k * c.Te, world.gimbal_angles,
                          world.gimbal_rates)
            if step.decision.reseeded and arrived is None:
                arrived = (k + 1) * c.Te
            rows.tick((k + 1) * c.Te, torques=[torque])
    assert arrived is not None and arrived <= 2 * bound, (arrived, bound)
    assert np.all(np.abs(truth(sensor)) < 0.01)


def test_the_models_one_sample_paths_are_its_array_paths(model):
    """f, h and their Jacobians for one state take plain floats (the per-step path the
    filters use); they give the array paths' numbers."""
    rng = np.random.default_rng(0)
    x, u = rng.uniform(-0.4, 0.4, (30, 4)), rng.uniform(-10, 10, (30, 2))
    for one, many in ((lambda a, b: model.f(a, b), model.f(x, u)),
                      (lambda a, b: model.f_jacobian(a, b), model.f_jacobian(x, u)),
                      (lambda a, b: model.h(a), model.h(x)),
                      (lambda a, b: model.h_jacobian(a), model.h_jacobian(x))):
        rows = np.array([one(a, b) for a, b in zip(x, u, strict=True)])
        np.testing.assert_allclose(rows, many, rtol=1e-12, atol=1e-20)


def test_a_small_kkl_in_four_states_follows_both_angles(model):
    """Algorithm 1 one dimension up: the default design with each of the five powers
    filtered by its own bank (q = 25), a small network trained on the head's model in
    about a second, run on MuJoCo's driven head (0.022 rad at the worst measured;
    ``scripts/kkl_two_axes.py`` trains the full-size one, docs/kkl_two_axes.md)."""
    from dataclasses import replace as changed

    from ledsim.experiment.observer_presets import DEFAULT_RATES, observer_preset
    from observer.kkl.fixed_gain import KKLDesign
    from observer.kkl.training import train_kkl

    design = KKLDesign.split(model.Te, DEFAULT_RATES, model.n_output)
    _, config = observer_preset("default", model.Te)
    kkl, _ = train_kkl(model, design, changed(config, n_samples=10_000, hidden=200,
                                              threads=1), progress=False)
    assert np.all(ekf_error(model, kind=lambda _: kkl) < 0.05)


def test_two_one_axis_kkls_side_by_side_follow_both_angles(model):
    """The decoupled design: each axis's pair over the boresight's detector sees that
    axis alone (gain and the other angle divide out), so a one-axis KKL per axis
    (:class:`~observer.kkl.decoupled.PerAxis`) estimates the head; small ones, trained
    in about a second each, follow the driven head (docs/kkl_two_axes.md measures the
    full-size ones)."""
    from dataclasses import replace as changed

    from ledsim.experiment.observer_presets import observer_preset
    from ledsim.physics.axis_model import AxisRatioModel
    from observer.kkl.decoupled import PerAxis
    from observer.kkl.training import train_kkl

    axes = [AxisRatioModel(model, a) for a in range(2)]
    ratios = axes[1].h(np.array([[0.1, 0.0]]))
    np.testing.assert_allclose(axes[1].split(model.h(np.array([0.3, 0.1, 0, 0]))),
                               ratios[0], rtol=1e-12)  # the azimuth divides out
    design, config = observer_preset("default", model.Te)
    config = changed(config, n_samples=10_000, hidden=200, decoder_hidden=200, threads=1)
    kkls = [train_kkl(m, design, config, progress=False)[0] for m in axes]

    def per_axis(_):
        return PerAxis(model, kkls, lambda y: [m.split(y) for m in axes])

    assert np.all(ekf_error(model, kind=per_axis) < 0.05)  # 1.7e-3 and 3.1e-2 measured


def test_the_filters_count_the_models_error_whatever_their_noise(model):
    """R grows by the model's share of each predicted power, for a sensor's noise that
    depends on the signal (a physical receiver's) or not."""
    from observer.baselines.ukf import UnscentedKalmanFilter

    for kind in (ExtendedKalmanFilter, UnscentedKalmanFilter):
        f = kind(model)
        y = model.h(np.zeros(4))
        ok = np.ones(model.n_output, dtype=bool)
        for signal in (True, False):
            f.signal_noise = signal
            base = model.measurement_noise.covariance(y) if signal else f.R
            np.testing.assert_allclose(np.diag(f.R_at(y, ok) - base),
                                       (model.model_error * y) ** 2, rtol=1e-12)
        assert f.counts_model_error
    # and the UKF's update hands R its predicted powers even when the noise does not
    # depend on them (before, it handed None, and the model's share went uncounted)
    ukf = UnscentedKalmanFilter(model)
    ukf.signal_noise = False
    seen = []
    given = ukf.R_at
    ukf.R_at = lambda y_pred, ok: seen.append(y_pred) or given(y_pred, ok)
    ukf.update(model.h(np.array([0.05, 0.02, 0.0, 0.0])))
    assert seen and seen[0] is not None
