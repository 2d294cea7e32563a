"""The posterior Cramér-Rao bound: exact where the Kalman filter is exact, silent where
a sample is withheld, and never beaten by an estimator beyond its Monte-Carlo error."""

import numpy as np
import pytest

from observer.pcrb import (
    BoundError,
    BoundTerms,
    posterior_crb,
    process_information,
    ratio_to_bound,
    steady_bound,
    trajectory_terms,
)

F = np.array([[1.0, 0.01], [0.0, 1.0]])
Q = np.diag([1e-4, 2e-4]) ** 2
P0 = np.diag([0.1, 0.1])


def kalman_covariances(H, R, measured=None):
    """The Kalman filter's filtered covariance of a linear-Gaussian plant."""
    P, out = P0.copy(), []
    for k, Hk in enumerate(H):
        if measured is not None:
            Hk = Hk[measured[k]]
        Rk = R[np.ix_(range(len(Hk)), range(len(Hk)))]
        if len(Hk):
            K = P @ Hk.T @ np.linalg.inv(Hk @ P @ Hk.T + Rk)
            P = (np.eye(2) - K @ Hk) @ P
        out.append(P)
        P = F @ P @ F.T + Q
    return np.array(out)


def test_on_a_linear_gaussian_plant_the_bound_is_the_kalman_filters_covariance():
    """The Kalman filter is efficient there: the bound must equal its covariance."""
    rng = np.random.default_rng(0)
    N = 300
    H = rng.normal(size=(N, 2, 2))  # time-varying, as a nonlinear h along a trajectory
    R = np.diag([1e-3, 1e-3])
    terms = trajectory_terms(np.broadcast_to(F, (N, 2, 2)), H, np.diag(R),
                             process_information([1e-4, 2e-4]))
    bound = posterior_crb(terms, np.linalg.inv(P0))
    np.testing.assert_allclose(bound, kalman_covariances(H, R), rtol=1e-6, atol=1e-14)


def test_a_withheld_sample_carries_no_information():
    N = 50
    H = np.broadcast_to(np.array([[1.0, 0.0], [0.5, 0.0]]), (N, 2, 2))
    measured = np.ones((N, 2), dtype=bool)
    measured[20:30] = False  # an occlusion
    measured[35, 1] = False  # one dropout
    q_inv = process_information([1e-4, 2e-4])
    Fs = np.broadcast_to(F, (N, 2, 2))
    bound = posterior_crb(trajectory_terms(Fs, H, 1e-3, q_inv, measured), np.linalg.inv(P0))
    R = np.diag([1e-3, 1e-3])
    np.testing.assert_allclose(bound, kalman_covariances(H, R, measured), rtol=1e-6)
    assert bound[29, 0, 0] > bound[19, 0, 0]  # it grows through the occlusion


def test_pooling_identical_trajectories_changes_nothing_and_pooling_averages():
    rng = np.random.default_rng(1)
    N = 40
    Fs = np.broadcast_to(F, (N, 2, 2))
    q_inv = process_information([1e-4, 2e-4])
    a = trajectory_terms(Fs, rng.normal(size=(N, 2, 2)), 1e-3, q_inv)
    b = trajectory_terms(Fs, rng.normal(size=(N, 2, 2)), 1e-3, q_inv)
    J0 = np.linalg.inv(P0)
    np.testing.assert_allclose(posterior_crb(BoundTerms.pooled([a, a, a]), J0),
                               posterior_crb(a, J0))
    pooled = BoundTerms.pooled([a, b])
    np.testing.assert_allclose(pooled.info / pooled.count, (a.info + b.info) / 2)
    again = BoundTerms.from_arrays(pooled.to_arrays())
    np.testing.assert_array_equal(again.info, pooled.info)
    assert again.count == 2


def test_bad_input_is_refused_with_the_value():
    with pytest.raises(BoundError, match=r"process_noise_std=\[0.0, 0.0002\]"):
        process_information([0.0, 2e-4])
    with pytest.raises(BoundError, match="must be"):
        trajectory_terms(np.zeros((3, 2, 2)), np.zeros((4, 2, 2)), 1.0, np.eye(2))
    a = trajectory_terms(np.zeros((3, 2, 2)), np.zeros((3, 2, 2)), 1.0, np.eye(2))
    b = trajectory_terms(np.zeros((4, 2, 2)), np.zeros((4, 2, 2)), 1.0, np.eye(2))
    with pytest.raises(BoundError, match="one configuration"):
        a + b


def test_the_kalman_filters_monte_carlo_error_meets_the_bound():
    """A check of the bound by Monte Carlo: 400 runs of the Kalman filter on a linear
    plant reach the bound's steady root within their Monte-Carlo error, from above."""
    rng = np.random.default_rng(2)
    N, S = 200, 400
    H = np.array([[1.0, 0.0]])
    R = np.array([[1e-3]])
    errs = np.empty((S, 2))
    for s in range(S):
        x = rng.multivariate_normal(np.zeros(2), P0)
        xh, P = np.zeros(2), P0.copy()
        e2 = np.zeros(2)
        for k in range(N):
            y = H @ x + rng.normal(0, np.sqrt(R[0, 0]), 1)
            K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
            xh = xh + K @ (y - H @ xh)
            P = (np.eye(2) - K @ H) @ P
            if k >= N // 2:
                e2 += (xh - x) ** 2
            x = F @ x + rng.multivariate_normal(np.zeros(2), Q)
            xh, P = F @ xh, F @ P @ F.T + Q
        errs[s] = np.sqrt(e2 / (N - N // 2))
    terms = trajectory_terms(np.broadcast_to(F, (N, 2, 2)), np.broadcast_to(H, (N, 1, 2)),
                             R[0, 0], process_information([1e-4, 2e-4]))
    bound = steady_bound(posterior_crb(terms, np.linalg.inv(P0)), N // 2)
    ratio, err = ratio_to_bound(errs, bound)
    assert np.all(np.abs(ratio - 1) < 3 * err + 1e-3), (ratio, err)
    assert np.all(err < 0.05)
