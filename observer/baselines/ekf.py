"""Extended Kalman filter, as used for LED alignment by Solanki et al. (2018)."""

from __future__ import annotations

import numpy as np

from observer import jit
from observer.estimator import GaussianFilter, usable_mask

compiled_ekf = jit.lazy("observer.baselines.compiled_ekf")


class ExtendedKalmanFilter(GaussianFilter):
    """EKF on the system's f and h with their Jacobians.

    Args:
        system: plant; its ``process_noise_std`` and ``measurement_noise_std`` give Q, R.
        P0: initial covariance (default: that of a uniform law on the domain).

    On the compiled path (:mod:`observer.jit`) a system that gives its f and h as numbers
    (``compiled_f``, ``compiled_h``: the identified one-axis gimbal model) with a noise
    that does not depend on the signal runs :mod:`observer.baselines.compiled_ekf`; this
    class's methods stay the reference.
    """

    name = "ekf"

    def _compiled_numbers(self) -> tuple | None:
        """The kernels' constants for this system, or None where the reference runs."""
        numbers = getattr(self, "_numbers", False)
        if numbers is False:
            s = self.system
            numbers = None
            if hasattr(s, "compiled_f") and hasattr(s, "compiled_h") \
                    and not self.signal_noise:
                self.contain_box()
                bounded = s.output_low is not None
                lo = np.asarray(s.output_low if bounded else np.zeros(s.n_output), float)
                hi = np.asarray(s.output_high if bounded else np.zeros(s.n_output), float)
                lo, hi = (np.ascontiguousarray(np.broadcast_to(a, (s.n_output,)))
                          for a in (lo, hi))
                # (R is read at each call: the filter's own, as the reference's)
                numbers = (lo, hi, bounded, *s.compiled_h(), None,
                           float(getattr(s, "model_error", 0.0)), *s.compiled_f(),
                           np.array(self._contained_box, dtype=float))
            self._numbers = numbers
        return numbers if jit.enabled() else None

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        c = self._compiled_numbers()
        if c is not None:
            x, P, self.inconsistent, diverged = compiled_ekf.update(
                self.x, self.P, y, *c[:6], self.R, c[7], float(self.noise_scale),
                float(self.lost_nis), int(self.lost_steps), int(self.inconsistent))
            if diverged:
                self.reset()
            else:
                self.x, self.P = x, P
            return self.x.copy()
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
        c = self._compiled_numbers()
        if c is not None and np.ndim(u) == 0:
            x, P, contained = compiled_ekf.predict(self.x, self.P, float(u), c[8], c[9],
                                                   self.Q, c[10])
            self.x, self.P = x, P
            if not contained:
                self.reset()
            return
        F = self.system.f_jacobian(self.x, u)
        self.x = self.system.f(self.x, u)
        self.P = F @ self.P @ F.T + self.Q
        self.contain()
