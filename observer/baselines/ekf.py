"""Extended Kalman filter, as used for LED alignment by Solanki et al. (2018)."""

from __future__ import annotations

import numpy as np

from observer.estimator import GaussianFilter, usable_mask


class ExtendedKalmanFilter(GaussianFilter):
    """EKF on the system's f and h with their Jacobians.

    Args:
        system: plant; its ``process_noise_std`` and ``measurement_noise_std`` give Q, R.
        P0: initial covariance (default: that of a uniform law on the domain).
    """

    name = "ekf"

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        ok = usable_mask(self.system, y)
        if ok.any():
            H = self.system.h_jacobian(self.x)[ok]
            y_pred = self.system.h(self.x)
            innov = (y - y_pred)[ok]
            R = self.R_at(y_pred, ok)
            S = H @ self.P @ H.T + R
            if self.diverged(innov, S):
                return self.x.copy()
            K = np.linalg.solve(S, H @ self.P).T
            self.x = self.x + K @ innov
            IKH = np.eye(self.x.size) - K @ H
            self.P = IKH @ self.P @ IKH.T + K @ R @ K.T  # Joseph form
        return self.x.copy()

    def predict(self, u) -> None:
        F = self.system.f_jacobian(self.x, u)
        self.x = self.system.f(self.x, u)
        self.P = F @ self.P @ F.T + self.Q
        self.contain()
