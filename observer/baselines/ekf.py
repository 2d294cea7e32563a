"""Extended Kalman filter, as used for LED alignment by Solanki et al. (2018)."""

from __future__ import annotations

import numpy as np

from ..estimator import Estimator, finite_mask
from ..system import DiscreteSystem


class ExtendedKalmanFilter(Estimator):
    """EKF on the system's f and h with their Jacobians.

    Args:
        system: plant; its ``process_noise_std`` and ``measurement_noise_std`` give Q, R.
        P0: initial covariance (default: that of a uniform law on the domain).
    """

    name = "ekf"

    def __init__(self, system: DiscreteSystem, P0: np.ndarray | None = None):
        super().__init__(system)
        self.Q = np.diag(system.process_noise_std**2)
        self.R = np.diag(system.measurement_noise_std**2)
        self.P0 = self.initial_covariance() if P0 is None else np.asarray(P0, dtype=float)
        self.reset()

    def reset(self, x0=None) -> None:
        self.x = self.initial_guess(x0)
        self.P = self.P0.copy()

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        ok = finite_mask(y)
        if ok.any():
            H = self.system.h_jacobian(self.x)[ok]
            innov = (y - self.system.h(self.x))[ok]
            S = H @ self.P @ H.T + self.R[np.ix_(ok, ok)]
            K = np.linalg.solve(S, H @ self.P).T
            self.x = self.x + K @ innov
            IKH = np.eye(self.x.size) - K @ H
            self.P = IKH @ self.P @ IKH.T + K @ self.R[np.ix_(ok, ok)] @ K.T  # Joseph form
        return self.x.copy()

    def predict(self, u) -> None:
        F = self.system.f_jacobian(self.x, u)
        self.x = self.system.f(self.x, u)
        self.P = F @ self.P @ F.T + self.Q
