"""The fixed-gain KKL's compiled update and predict (observer/kkl/compiled_fixed.py)
against the numpy reference: the default pan-tilt head's per-axis KKLs over recorded
runs, and one axis's observer on inputs that leave its box or miss an output."""

from __future__ import annotations

import numpy as np
import pytest

from observer import jit
from tests.test_compiled import KINDS, compiled_differences

pytestmark = pytest.mark.skipif(not jit.installed(), reason="numba is not installed")


@pytest.mark.parametrize("kinds", KINDS, ids=lambda k: k[0].split(":")[0] if k else "none")
def test_the_default_heads_compiled_kkl_gives_the_references_estimates(kinds, monkeypatch):
    """The CLI's default run (the pan-tilt with its quad on ``luma``): a fresh per-axis
    KKL given a run's calls, on the reference path bit for bit, on the compiled path
    within round-off at every update."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    cfg = RunConfig(seconds=2.0, disturbances=kinds, link="luma")
    with jit.use(False):
        series = run_once(cfg, 1, keep_trace=True).trace.series()

    def runs_compiled(est):
        assert all(e._compiled_numbers() is not None for e in est.axes)

    d = compiled_differences(cfg, series, monkeypatch, runs_compiled)
    assert d.size > 100
    assert d.max() <= 1e-11, d.max()  # measured: 1.6e-13 at most, medians 3e-14 to 4e-14
    assert np.median(d) <= 1e-13, np.median(d)


def _axis_observer():
    from ledsim.loop.build.control import head_model
    from ledsim.loop.build.estimation import identified_model
    from ledsim.loop.build.head_kkl import head_kkl
    from ledsim.loop.run_config import RunConfig
    from ledsim.physics.head_system import HeadSystem

    cfg = RunConfig(link="luma")
    system = HeadSystem(cfg.world_config())
    return head_kkl(head_model(cfg, identified_model(system))).axes[0]


def test_the_compiled_fixed_kkl_steps_as_the_reference_off_its_box_and_without_outputs():
    """Outputs missing or off their bounds (held at h(x_hat)), inputs at u_bar (no
    Omega) and large enough to drive f out of the box: the same flag at every step on
    both paths and the same z to round-off; a perturbed encoder in the kernel fails."""
    obs = _axis_observer()
    rng = np.random.default_rng(5)
    n = 300
    ys = 1.0 + 0.05 * rng.standard_normal((n, 2))
    ys[40] = np.nan
    ys[50:55, 1] = np.inf
    ys[60, 0] = -1.0  # below any ratio
    u = rng.normal(scale=2.0, size=n)
    u[::7] = obs.u_bar
    u[200:210] = 1e4  # drives f far out of the box
    runs = {}
    for compiled in (False, True):
        with jit.use(compiled):
            obs.reset()
            rows = []
            for k in range(n):
                x = obs.update(ys[k])
                rows.append(np.r_[x, obs._y, obs.outside_domain])
                obs.predict(float(u[k]))
                rows.append(np.r_[obs.z[:4], obs.outside_domain])
            runs[compiled] = np.array(rows)
    ref, got = runs[False], runs[True]
    assert ref[:, 4].any() and not ref[:, 4].all()  # both sides of the box were seen
    np.testing.assert_array_equal(got[:, 4], ref[:, 4])
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12)
    with jit.use(True):  # the comparison can fail: a kernel with another encoder
        obs.reset()
        obs.update(ys[0])
        c = obs._compiled_numbers()
        W1T, b1, W2, b2 = c[6]
        z_ref, _ = _step(obs, c, W1T, b1, W2, b2)
        z_bad, _ = _step(obs, c, W1T, b1, W2 * (1 + 1e-6), b2)
        assert np.abs(z_bad - z_ref).max() > 1e-9


def _step(obs, c, W1T, b1, W2, b2):
    from observer.kkl import compiled_fixed

    return compiled_fixed.predict(obs.z, obs._y, obs._xhat, 0.5, obs.u_bar, True,
                                  obs.eigenvalues, obs.B, *c[0], W1T, b1, W2, b2, *c[1:3])


def test_the_compiled_axis_fix_is_the_references_to_the_bit():
    """A pan-tilt axis's fix from the head's powers: the same angle, or the same None
    (a missing or dark power, off the grid, a shaded photodiode), on both paths."""
    system = _axis_observer().system
    head = system.head
    rng = np.random.default_rng(6)
    outcomes = set()
    for k in range(3000):
        x = np.array([rng.normal(scale=0.3), rng.normal(scale=0.3), 0.0, 0.0])
        y = head.h(x) * (1 + rng.normal(scale=0.02, size=head.n_output))
        if k % 7 == 0:
            y[rng.integers(y.size)] *= rng.choice([0.0, 0.3, np.nan, -1.0, 3.0])
        with jit.use(False):
            ref = system.fix(y)
        with jit.use(True):
            got = system.fix(y)
        assert (ref is None and got is None) or (ref == got and type(got) is float), \
            (y, ref, got)
        outcomes.add(ref is None)
    assert outcomes == {True, False}
