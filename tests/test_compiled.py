"""The compiled kernels (observer/jit.py) against their numpy reference: the same
numbers to round-off, step by step, over recorded runs of every disturbance kind."""

from __future__ import annotations

import numpy as np
import pytest

from observer import jit
from observer.kkl.gainmaps import GainTableMap

pytestmark = pytest.mark.skipif(not jit.installed(), reason="numba is not installed")

KINDS = ((), ("vibration:frequency=3,torque=0.5,force=2",), ("current:speed=0.3,gust=0.05",),
         ("waves:height=1,period=6",), ("transmitter:sway=0.005,yaw=0.1",),
         ("occlusion:start=1,duration=0.5",), ("kick:start=1,rate=8",),
         ("kick:start=1,rate=3,hull=1",), ("dvl_dropout:start=0.5,duration=1",))


def test_the_compiled_tanh_is_within_2_ulp_of_numpys_over_the_whole_line():
    from observer.kkl.compiled_maps import tanh_inplace

    x = np.concatenate([np.linspace(-30, 30, 600_001), np.geomspace(1e-300, 2, 20_000),
                        -np.geomspace(1e-300, 2, 20_000),
                        [0.0, -0.0, 0.625, -0.625, np.nextafter(0.625, 0), 19.1, -19.1,
                         1e300, -1e300, np.inf, -np.inf]])
    h = x.copy()
    tanh_inplace(h, np.empty(h.size, np.int64))
    ref = np.tanh(x)
    ulps = np.abs(h - ref) / np.spacing(np.maximum(np.abs(ref), np.finfo(float).tiny))
    assert ulps.max() <= 2.0
    assert np.array_equal(np.signbit(h), np.signbit(ref))  # -0.0 stays -0.0
    nan = np.array([np.nan])
    tanh_inplace(nan, np.empty(1, np.int64))
    assert np.isnan(nan[0])


def _random_map(rng, shared: bool, n_in=3, H=40, n_out=4, n_w=5, n_s=3) -> GainTableMap:
    W1 = rng.normal(size=(H, n_in) if shared else (n_w, H, n_in))
    b1 = rng.normal(size=(H,) if shared else (n_w, H))
    coef = rng.normal(size=(n_w, n_s, n_out, H + 1))
    return GainTableMap(W1, b1, coef, np.linspace(-3, 1, n_w), np.linspace(0, 2, n_s))


@pytest.mark.parametrize("shared", [True, False])
def test_a_compiled_map_is_the_numpy_map_to_round_off(shared):
    """On and between the grid points of both the gain and the noise, and beyond them
    (clipped), on one sample and on a few."""
    rng = np.random.default_rng(3)
    m = _random_map(rng, shared)
    for w in (np.exp(-3), 0.2, np.exp(-2), 1.5, np.exp(1), 9.0, 0.01):
        for s in (1.0, 1.7, np.exp(1), 5.0, 30.0):
            for v in (rng.normal(size=3), rng.normal(size=(2, 1, 3)), rng.normal(size=(4, 3))):
                with jit.use(False):
                    ref = m(v, w, s)
                with jit.use(True):
                    out = m(v, w, s)
                assert out.shape == ref.shape
                assert np.all(np.abs(out - ref) <= 1e-12 * (1 + np.abs(ref))), (w, s, out - ref)


def test_a_batch_takes_numpys_path():
    """The compiled map is for a step's few samples; training's batches stay numpy's."""
    rng = np.random.default_rng(4)
    m = _random_map(rng, False)
    v = rng.normal(size=(50, 3))
    with jit.use(True):
        out = m(v, 0.3, 1.2)
    with jit.use(False):
        assert np.array_equal(out, m(v, 0.3, 1.2))


@pytest.fixture(scope="module")
def traces():
    """The KKL's calls in a 2 s run of each disturbance kind, on the reference path."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    out = []
    with jit.use(False):
        for kinds in KINDS:
            cfg = RunConfig(seconds=2.0, disturbances=kinds)
            out.append((cfg, run_once(cfg, 1, keep_trace=True).trace.series()))
    return out


def compiled_differences(cfg, series, monkeypatch, check=None) -> np.ndarray:
    """A fresh estimator of ``cfg`` given a run's recorded calls ``series``: asserts that
    the reference path replays them bit for bit, and returns the compiled path's
    difference at every replayed call (``check``: called with the compiled estimator
    before the replay)."""
    import observer.recording as recording
    from ledsim.loop.replay import run_estimator

    with jit.use(False):
        assert recording.replay_calls(run_estimator(cfg), series) == 0.0
    diffs = []
    exact = recording.difference
    monkeypatch.setattr(recording, "difference",
                        lambda x, out, d=diffs, f=exact: d.append(f(x, out)) or d[-1])
    with jit.use(True):
        est = run_estimator(cfg)
        if check is not None:
            check(est)
        recording.replay_calls(est, series)
    monkeypatch.setattr(recording, "difference", exact)
    return np.array(diffs)


def test_the_compiled_kkl_gives_the_references_estimates_over_every_disturbance(
        traces, monkeypatch):
    """A fresh KKL given a run's calls: on the reference path bit for bit, on the
    compiled path within round-off at every update of every run. Measured: 1e-13 rad
    once converged (most steps); up to 1e-6 rad while the estimate converges, from its initial guess
    or after a kick (off by radians), through the decoder's steepest region, where
    1e-16 of z becomes 1e-7 of phi. The differences do not grow: z is a stable
    filter."""
    for cfg, series in traces:
        d = compiled_differences(cfg, series, monkeypatch)
        assert d.max() <= 1e-5, (cfg.disturbances, d.max())
        assert np.median(d) <= 1e-12, (cfg.disturbances, np.median(d))


def test_the_compiled_shape_inversion_is_the_references():
    """The pair's shape inversion and its phi's variance (the gain tracker's and the
    fading channel's per-step optics) over powers from dark to saturated, with a dark,
    a negative and a missing one: the same to 1e-15, inf and NaN where the reference has
    them."""
    import math

    from ledsim.constants import LinkConstants
    from ledsim.radiometry.optics import pair_phi_variance, pair_shape_inverse

    c = LinkConstants()
    rng = np.random.default_rng(5)
    pairs = [rng.uniform(1e-9, 3e-5, 2) for _ in range(3000)]
    pairs += [np.array(p) for p in ([0.0, 1e-5], [-1e-7, 1e-5], [np.nan, 1e-5], [1e-5, 1e-30],
                                    [3e-5, 1e-12])]
    for p in pairs:
        got, want = [], []
        for compiled, out in ((True, got), (False, want)):
            with jit.use(compiled), np.errstate(divide="ignore"):  # numpy's 1 / 0
                out.extend(pair_shape_inverse(p, c))
                out.append(pair_phi_variance(0.1, p, 1e-7, c))
        for g, w in zip(got, want, strict=True):
            assert (math.isnan(g) and math.isnan(w)) or g == w or \
                abs(g - w) <= 1e-15 * abs(w), (p, got, want)


def test_the_compiled_monitor_decides_as_the_reference():
    """A random walk of the estimate with the light gone, a photodiode missing, a
    non-finite estimate, a jump out of the domain and re-seeds: the same decision and
    reason at every step, the statistic and the noise level to round-off."""
    from ledsim.loop.build.estimation import identified_model
    from ledsim.physics.gimbal_system import GimbalSystem
    from ledsim.physics.scene import WorldConfig
    from observer.supervision.monitor import ResidualMonitor

    model = identified_model(GimbalSystem(WorldConfig()))
    rng = np.random.default_rng(0)
    n = 3000
    xs = np.cumsum(rng.normal(scale=0.01, size=(n, 2)), 0) * 0.3
    ys = np.array([model.h(x) for x in xs]) + rng.normal(scale=2e-7, size=(n, 2))
    ys[500:520] = np.nan
    ys[900:1000] *= 1e-4
    ys[1500:1550, 0] = np.nan
    xs[2000] = np.nan
    xs[2500:2600] += 0.8
    reasons = set()
    for threshold in (25.0, 1e12):  # the second never flags the residual: the dark does
        with jit.use(False):
            ref = ResidualMonitor(model, threshold=threshold)
        with jit.use(True):
            com = ResidualMonitor(model, threshold=threshold)
        assert com._kernel is not None and ref._kernel is None
        for k in range(n):
            if k in (1200, 2700):
                ref.reset()
                com.reset()
            assert ref.update(ys[k], xs[k]) == com.update(ys[k], xs[k]), k
            assert ref.reason == com.reason, k
            reasons.add(ref.reason)
            assert abs(ref.statistic - com.statistic) <= 1e-14 * abs(ref.statistic), k
            assert np.allclose(ref.noise_var, com.noise_var, rtol=1e-14, atol=0), k
    assert {"", "no light", "non-finite estimate", "estimate outside the domain",
            "output residual above the noise"} <= reasons


def test_the_compiled_gain_tracker_and_fading_channel_follow_the_reference():
    """A fading pair (scintillation on both photodiodes, a drifting gain, the encoder
    turning), with dark and missing samples: every state of the tracker and its channel
    to round-off at every step, and the same decisions (the fade learned, the ratio
    moved)."""
    from ledsim.agent.link_gain import link_gain_tracker
    from ledsim.loop.build.estimation import identified_model
    from ledsim.physics.gimbal_system import GimbalSystem
    from ledsim.physics.scene import WorldConfig

    system = GimbalSystem(WorldConfig())
    model, c = identified_model(system), system.constants
    with jit.use(False):
        ref = link_gain_tracker(model, c, 1.1)
    with jit.use(True):
        com = link_gain_tracker(model, c, 1.1)
    rng = np.random.default_rng(7)
    n = 1500
    phi = 0.05 * np.sin(np.arange(n) * 0.01)
    gain = 1.1 * np.exp(np.cumsum(rng.normal(scale=2e-3, size=n)))
    fade = np.exp(rng.normal(scale=0.2, size=n))
    y = (gain * fade)[:, None] * np.array([model.h(np.array([p, 0.0])) for p in phi])
    y += rng.normal(scale=float(np.mean(model.measurement_noise_std)), size=y.shape)
    y[300:320] = 0.0
    y[600:610, 0] = np.nan
    q = -phi + 0.001 * rng.normal(size=n)
    fades = []
    for k in range(n):
        qk = None if 800 <= k < 850 else float(q[k])
        for tracker, compiled in ((ref, False), (com, True)):
            with jit.use(compiled):
                tracker.sample(y[k], qk, 1e-8)
                tracker.update(y[k])
        fades.append(ref.fade)
        assert abs(ref.fade - com.fade) <= 1e-12 * ref.fade, k
        for a, b in ((ref._s, com._s), (ref._P, com._P), ((ref.ratio,), (com.ratio,))):
            assert np.allclose(a, b, rtol=1e-12, atol=1e-300), k
        ch, cc = ref.channel, com.channel
        assert ch._learned == cc._learned and (ch._last is None) == (cc._last is None), k
        assert np.allclose([ch.step_variance, ch.noise_variance, ch.shape_step_variance,
                            ch.shape_noise_variance],
                           [cc.step_variance, cc.noise_variance, cc.shape_step_variance,
                            cc.shape_noise_variance], rtol=1e-12, atol=0), k
    assert max(fades) > 1.1 and ref.ratio != 1.1  # a fade was learned, the gain moved


def test_the_warm_up_says_when_the_compiled_path_is_off():
    import os
    import subprocess
    import sys

    env = dict(os.environ, LEDSIM_COMPILED="0")
    p = subprocess.run([sys.executable, "-m", "ledsim.loop.warm"], capture_output=True,
                       text=True, env=env, timeout=120)
    assert p.returncode == 0 and "the compiled path is off" in p.stdout, p.stderr


def test_a_kernel_compiles_without_its_cache_where_numba_has_nowhere_to_write_it(monkeypatch):
    """A read-only install with no writable home: numba finds no cache locator. The kernel
    then compiles in the process (it once surfaced as a 'corrupt checkpoint')."""
    import numba.core.caching as caching

    monkeypatch.setattr(caching.CacheImpl, "_locator_classes", [])

    def twice(x):
        return 2.0 * x

    kernel = jit.njit()(twice)
    assert kernel(1.5) == 3.0
    assert type(kernel._cache).__name__ == "NullCache"  # compiled, not cached

    def thrice(x):
        return 3.0 * x

    with pytest.raises(RuntimeError, match="no locator"):  # what numba itself does
        import numba

        numba.njit(cache=True)(thrice)
