"""The EKF's compiled update and predict (observer/baselines/compiled_ekf.py) against the
numpy reference: its estimates over recorded runs, and its restarts (a diverged filter,
a run-away mean) at the same steps."""

from __future__ import annotations

import numpy as np
import pytest

from observer import jit
from tests.test_compiled import compiled_differences

pytestmark = pytest.mark.skipif(not jit.installed(), reason="numba is not installed")

KINDS = ((), ("vibration:frequency=3,torque=0.5,force=2",), ("occlusion:start=1,duration=0.5",),
         ("kick:start=1,rate=8",), ("kick:start=1,rate=3,hull=1",))


@pytest.mark.parametrize("kinds", KINDS, ids=["none", "vibration", "occlusion", "kick",
                                              "hull_kick"])
def test_the_compiled_ekf_gives_the_references_estimates(kinds, monkeypatch):
    """A fresh EKF given a run's calls: on the reference path bit for bit, on the
    compiled path within round-off at every update (measured: 7e-15 at most, a median
    of 2e-17)."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    cfg = RunConfig(seconds=2.0, disturbances=kinds, estimator="ekf")
    with jit.use(False):
        series = run_once(cfg, 1, keep_trace=True).trace.series()

    def runs_compiled(est):
        assert est._compiled_numbers() is not None

    d = compiled_differences(cfg, series, monkeypatch, runs_compiled)
    assert d.size > 100
    assert d.max() <= 1e-12, d.max()
    assert np.median(d) <= 1e-15, np.median(d)


def test_the_compiled_ekf_restarts_where_the_reference_does():
    """Garbage powers for long enough (the divergence count), a dark step, one output
    missing, and inputs that run the mean away (the containment): the same state at
    every step on both paths, the restarts included."""
    from ledsim.loop.build.estimation import identified_model
    from ledsim.physics.gimbal_system import GimbalSystem
    from ledsim.physics.scene import WorldConfig
    from observer.baselines import ExtendedKalmanFilter

    model = identified_model(GimbalSystem(WorldConfig()))
    rng = np.random.default_rng(2)
    n = 400
    ys = np.array([model.h(np.array([0.1 * np.sin(k / 30), 0.0])) for k in range(n)])
    ys = ys + rng.normal(scale=2e-7, size=ys.shape)
    ys[100:180] = ys[100:180, ::-1] * 5.0  # implausible for 80 steps: a divergence
    ys[200] = np.nan
    ys[210:220, 1] = np.nan
    u = np.where((np.arange(n) >= 300) & (np.arange(n) < 330), 1e6, 0.0)  # a run-away
    filters = {}
    for compiled in (False, True):
        with jit.use(compiled):
            f = ExtendedKalmanFilter(model)
            f.tell_noise_scale(1.5)
            states = []
            for k in range(n):
                states.append(np.r_[f.update(ys[k]), f.P.ravel(), f.inconsistent])
                f.predict(u[k])
                states.append(np.r_[f.x, f.P.ravel(), f.inconsistent])
            filters[compiled] = np.array(states)
    ref, got = filters[False], filters[True]
    resets = np.flatnonzero(np.all(ref[:, :2] == ExtendedKalmanFilter(model).x, axis=1))
    assert len(resets) >= 2  # both restarts happened
    np.testing.assert_array_equal(got[:, -1], ref[:, -1])  # the same count, every step
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12)


def test_a_noise_covariance_set_after_the_first_step_reaches_the_compiled_path():
    """R is the filter's own at every call, not a copy taken on the first."""
    from ledsim.loop.build.estimation import identified_model
    from ledsim.physics.gimbal_system import GimbalSystem
    from ledsim.physics.scene import WorldConfig
    from observer.baselines import ExtendedKalmanFilter

    model = identified_model(GimbalSystem(WorldConfig()))
    rng = np.random.default_rng(8)
    ys = np.array([model.h(np.array([0.05, 0.0]))] * 60) + rng.normal(scale=2e-7,
                                                                      size=(60, 2))
    states = {}
    for compiled in (False, True):
        with jit.use(compiled):
            f = ExtendedKalmanFilter(model)
            out = []
            for k, y in enumerate(ys):
                if k == 20:
                    f.R = f.R * 25.0  # five times the noise from here on
                out.append(np.r_[f.update(y), f.P.ravel()])
                f.predict(0.0)
            states[compiled] = np.array(out)
    np.testing.assert_allclose(states[True], states[False], rtol=1e-9, atol=1e-15)
