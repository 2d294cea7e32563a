"""Unscented Kalman filter with Van der Merwe's scaled sigma points."""

from __future__ import annotations

import numpy as np

from observer.estimator import GaussianFilter, usable_mask
from observer.system import DiscreteSystem


def nearest_covariance(P: np.ndarray, floor: float = 1e-12) -> np.ndarray:
    """The symmetric matrix nearest to ``P`` with eigenvalues >= ``floor`` x its scale."""
    S = 0.5 * (P + P.T)
    if not np.all(np.isfinite(S)):
        raise np.linalg.LinAlgError("covariance is not finite")
    w, V = np.linalg.eigh(S)
    w = np.maximum(w, floor * max(float(np.abs(w).max()), 1e-300))
    return (V * w) @ V.T


class UnscentedKalmanFilter(GaussianFilter):
    """UKF (Wan & Van der Merwe 2000) on the system's f and h.

    Args:
        system: plant; its noise levels give Q and R.
        alpha, beta, kappa: sigma-point spread parameters.
        P0: initial covariance (default: uniform law on the domain).
    """

    name = "ukf"

    def __init__(self, system: DiscreteSystem, alpha: float = 0.5, beta: float = 2.0,
                 kappa: float = 1.0, P0: np.ndarray | None = None):
        n = system.n_state
        self.lam = alpha**2 * (n + kappa) - n
        self.Wm = np.full(2 * n + 1, 0.5 / (n + self.lam))
        self.Wc = self.Wm.copy()
        self.Wm[0] = self.lam / (n + self.lam)
        self.Wc[0] = self.Wm[0] + 1 - alpha**2 + beta
        super().__init__(system, P0)

    def sigma_points(self) -> np.ndarray:
        n = self.x.size
        try:
            L = np.linalg.cholesky((n + self.lam) * self.P)
        except np.linalg.LinAlgError:  # P lost positive definiteness to round-off
            self.P = nearest_covariance(self.P)
            L = np.linalg.cholesky((n + self.lam) * self.P)
        return np.vstack([self.x, self.x + L.T, self.x - L.T])

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        ok = usable_mask(self.system, y)
        if ok.any():
            X = self.sigma_points()
            Y_all = self.system.h(X)
            Y = Y_all[:, ok]
            y_mean = self.Wm @ Y
            dY = Y - y_mean
            dX = X - self.x
            S = (self.Wc * dY.T) @ dY + self.R_at(
                self.Wm @ Y_all if self.signal_noise or self.counts_model_error else None,
                ok)
            C = (self.Wc * dX.T) @ dY
            if self.diverged(y[ok] - y_mean, S):
                return self.x.copy()
            K = np.linalg.solve(S, C.T).T
            self.x = self.x + K @ (y[ok] - y_mean)
            self.P = self.P - K @ S @ K.T
            self.P = 0.5 * (self.P + self.P.T)
        return self.x.copy()

    def predict(self, u) -> None:
        X = self.system.f(self.sigma_points(), u)
        self.x = self.Wm @ X
        dX = X - self.x
        self.P = (self.Wc * dX.T) @ dX + self.Q
        self.contain()
