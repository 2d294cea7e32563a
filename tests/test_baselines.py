import copy

import numpy as np
import pytest

from ledsim.paper.scenarios import Noise, get_scenario, run
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
from observer.metrics import converged, rmse


@pytest.mark.parametrize("make", [ExtendedKalmanFilter, UnscentedKalmanFilter,
                                  lambda s: ParticleFilter(s, 1000)])
def test_filter_tracks_open_loop_from_centre(system, make):
    sc = get_scenario("open-loop")
    out = run(system, sc, make(system), Noise.draw(system, sc.n_steps(system.Te), 0))
    assert np.all(rmse(out.xhat, out.x, sc.steady_step(system.Te)) < [6e-3, 1e-2])


@pytest.mark.parametrize("make", [ExtendedKalmanFilter, UnscentedKalmanFilter,
                                  lambda s: ParticleFilter(s, 500)])
def test_filters_skip_missing_measurements(system, make):
    est = make(system)
    est.reset()
    x_before = est.update(np.array([np.nan, np.nan]))
    np.testing.assert_allclose(x_before, system.domain_center, atol=0.05)
    est.predict(0.0)
    twin = copy.deepcopy(est)
    x_pred = twin.update(np.array([np.nan, np.nan]))  # nothing measured: the prediction
    x = est.update(np.array([np.nan, 0.9]))  # photodiode 2 only
    assert np.all(np.isfinite(x))
    # The one finite power was used: the estimate left the prediction.
    assert np.linalg.norm(x - x_pred) > 1e-3


def test_convergence_flag_separates_locked_from_tracking_estimates():
    t = np.linspace(0, 1, 100)
    truth = np.stack([0.1 * t, 0 * t], -1)
    good = truth + 0.001
    wrong_branch = truth * [-1, 1] + [0.05, 0]  # mirror image across the peak
    assert converged(good, truth, 50)
    assert not converged(wrong_branch, truth, 50)


def test_a_filter_whose_mean_runs_away_starts_again(system):
    """Predictions without updates through a nonlinear f can square a bad mean step
    after step; the filters start again from the domain's centre instead of overflowing."""
    from observer.baselines.ekf import ExtendedKalmanFilter
    from observer.baselines.ukf import UnscentedKalmanFilter

    for cls in (ExtendedKalmanFilter, UnscentedKalmanFilter):
        f = cls(system)
        centre = 0.5 * (system.domain_low + system.domain_high)
        f.x = centre + 1e3 * (system.domain_high - system.domain_low)
        f.predict(0.0)
        assert np.all(np.isfinite(f.x))
        np.testing.assert_allclose(f.x, f.initial_guess(None))
        f.x = centre + 0.5 * (system.domain_high - centre)  # an ordinary excursion stays
        f.predict(0.0)
        assert np.all(np.abs(f.x - centre) < system.domain_high - centre)
