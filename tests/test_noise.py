"""One noise object: the sensor, the estimators' R, the supervisor, the env and the link
budget read the same :class:`~observer.noise.MeasurementNoise`."""

import numpy as np
import pytest

from ledsim.constants import LinkConstants
from ledsim.envs.link_align import LinkAlignEnv
from ledsim.loop.closed_loop import ClosedLoop
from ledsim.loop.run_config import RunConfig
from observer.noise import MeasurementNoise


def test_noise_object_draws_what_it_says():
    n = MeasurementNoise(0.03, 2, 2.0)
    assert n.std == pytest.approx(0.06)
    assert n.scaled(0.5).std == pytest.approx(0.03)
    assert n.nominal().std == 0.03
    np.testing.assert_allclose(n.covariance(), np.diag([0.06**2] * 2))
    draws = np.array([n.sample(np.random.default_rng(k)) for k in range(4000)])
    assert draws.shape == (4000, 2)
    np.testing.assert_allclose(draws.std(axis=0), 0.06, rtol=0.05)


@pytest.mark.parametrize("bad", [dict(nominal_std=-1.0), dict(nominal_std=float("nan")),
                                 dict(nominal_std=1.0, scale=-2.0),
                                 dict(nominal_std=1.0, n_output=0)])
def test_noise_object_refuses_bad_values(bad):
    with pytest.raises(ValueError, match="is not allowed"):
        MeasurementNoise(**bad)


def test_the_link_constants_give_the_noise_object():
    c = LinkConstants(measurement_noise_var=4e-4)
    assert c.measurement_noise().std == pytest.approx(0.02)
    assert c.measurement_noise(3.0).std == pytest.approx(0.06)


def test_a_run_reads_one_noise_object():
    # The warm-up holds the gimbal still for these 0.2 s at either noise, so the
    # signal is the same and the SNRs differ by the noise alone.
    loop = ClosedLoop(RunConfig(seconds=0.2, noise_scale=2.5, acquisition="warm-up"), [3])
    run = loop.runs[0]
    assert run.sensor.measurement_noise is run.noise
    assert run.noise.std == pytest.approx(2.5 * loop.system.constants.measurement_noise_std)
    assert run.sensor.noise_std == run.noise.std
    # The supervisor's noise prior is the same noise in its model's nominal units.
    supervisor = run.step.supervisor
    np.testing.assert_allclose(supervisor.sensor_noise * supervisor.monitor.sigma0,
                               run.noise.std, rtol=1e-12)
    # The link budget is that noise's: an SNR 2.5^2 below the nominal run's.
    out = loop.run(False)[0]
    nominal = ClosedLoop(RunConfig(seconds=0.2, acquisition="warm-up"), [3]).run(False)[0]
    assert nominal.metrics.snr_db - out.metrics.snr_db == pytest.approx(
        20 * np.log10(2.5), abs=0.3)


def test_the_env_reads_one_noise_object():
    env = LinkAlignEnv(noise_scale=2.0, imu=False)
    try:
        env.reset(seed=1)
        assert env.sensor.measurement_noise is env.measurement_noise
        assert env.measurement_noise.std == pytest.approx(
            2.0 * env.system.constants.measurement_noise_std)
        assert env.observation_space.low[0] == pytest.approx(-20 * env.measurement_noise.std)
    finally:
        env.close()
