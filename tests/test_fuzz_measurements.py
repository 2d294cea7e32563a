"""Every estimator survives any measurement stream and recovers when valid data return.

A 20 s open-loop run of the closed-form model; from 5 s to 7 s (in the soak,
``scripts/soak.py``, for a random 0.01-5 s) the measurements are replaced by a hostile
stream, then the true ones return. The state must stay finite all
along, and the estimate must be back on the truth over the last 5 s.
"""

import os

import numpy as np
import pytest

from ledsim.paper.scenarios import Noise, get_scenario
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter

HOSTILE = {
    "nan": lambda y, rng: np.full_like(y, np.nan),
    "inf": lambda y, rng: np.full_like(y, np.inf),
    "+1e308": lambda y, rng: np.full_like(y, 1e308),
    "-1e308": lambda y, rng: np.full_like(y, -1e308),
    "-5 W": lambda y, rng: np.full_like(y, -5.0),
    "1e6 W": lambda y, rng: np.full_like(y, 1e6),
    "stuck": lambda y, rng: np.broadcast_to(y[0], y.shape).copy(),
    "random dropouts": lambda y, rng: np.where(rng.random(y.shape) < 0.5, np.nan, y),
    "mixed garbage": lambda y, rng: rng.choice(
        np.array([np.nan, np.inf, -np.inf, 1e308, -1e308, -5.0, 1e6, 0.0]), size=y.shape),
}
ESTIMATORS = {
    "kkl": None,  # the tiny observer fixture
    "ekf": ExtendedKalmanFilter,
    "ukf": UnscentedKalmanFilter,
    "pf": lambda s: ParticleFilter(s, 500),
}


def run_stream(system, est, kind, seed=0):
    sc = get_scenario("open-loop")
    n = sc.n_steps(system.Te)
    noise = Noise.draw(system, n, seed)
    x = np.asarray(sc.x0, dtype=float)
    xs = np.empty((n, 2))
    for k in range(n):
        xs[k] = x
        x = system.f(x, 0.0) + noise.process[k]
    ys = system.h(xs) + noise.measurement
    rng = np.random.default_rng(seed)
    # 2 s of hostile data; the soak's other seeds draw the length (0.01-5 s).
    bad = slice(500, 700 if seed == 0 else 500 + int(rng.integers(1, 501)))
    ys[bad] = HOSTILE[kind](ys[bad], rng)
    est.reset()
    xh = np.empty((n, 2))
    for k in range(n):
        xh[k] = est.update(ys[k])
        est.predict(0.0)
    return xs, xh


#: Noise seeds of each stream; ``scripts/soak.py`` runs more.
SEEDS = range(int(os.environ.get("LEDSIM_SOAK_STREAMS", "1")))


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("kind", list(HOSTILE))
@pytest.mark.parametrize("name", list(ESTIMATORS))
def test_estimator_survives_and_recovers(system, tiny_observer, name, kind, seed):
    est = tiny_observer if name == "kkl" else ESTIMATORS[name](system)
    xs, xh = run_stream(system, est, kind, seed)
    assert np.all(np.isfinite(xh)), "the estimate went non-finite"
    err = np.sqrt(np.mean((xh[1500:] - xs[1500:]) ** 2, axis=0))
    assert err[0] < 0.01 and err[1] < 0.05, err
