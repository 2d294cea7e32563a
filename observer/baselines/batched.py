"""The Kalman filters and the particle filter over N trajectories at once (see
:mod:`observer.batched`): the single filters' equations on (N, ...) arrays."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..batched import BatchedEstimator
from ..estimator import GaussianFilter
from .pf import ParticleFilter
from .ukf import UnscentedKalmanFilter, nearest_covariance


class _BatchedGaussian(BatchedEstimator):
    """Mean (N, n), covariance (N, n, n) and the divergence restart of
    :class:`~observer.estimator.GaussianFilter`."""

    def __init__(self, template: GaussianFilter, n: int):
        super().__init__(template, n)
        self.Q, self.R, self.P0 = template.Q, template.R, template.P0
        self.lost_nis, self.lost_steps = template.lost_nis, template.lost_steps
        self.reset()

    def reset(self, x0=None) -> None:
        self.x = self._guess(x0)
        self.P = np.broadcast_to(self.P0, (self.n,) + self.P0.shape).copy()
        self.inconsistent = np.zeros(self.n, dtype=int)

    def _diverged(self, k: np.ndarray, innov: np.ndarray, S: np.ndarray) -> np.ndarray:
        """Per trajectory of ``k``: count an implausible innovation; restart (and report
        True) those that had too many in a row."""
        nis = np.einsum("ni,ni->n", innov, np.linalg.solve(S, innov[..., None])[..., 0])
        bad = nis > self.lost_nis * innov.shape[-1]
        self.inconsistent[k] = np.where(bad, self.inconsistent[k] + 1, 0)
        restart = self.inconsistent[k] >= self.lost_steps
        if restart.any():
            r = k[restart]
            self.x[r] = self.system.domain_center
            self.P[r] = self.P0
            self.inconsistent[r] = 0
        return restart


class BatchedEKF(_BatchedGaussian):
    """:class:`ExtendedKalmanFilter` over N trajectories."""

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        sys = self.system
        for k, ok in self.usable_groups(y):
            x, P = self.x[k], self.P[k]
            H = sys.h_jacobian(x)[:, ok]
            innov = (y[k] - sys.h(x))[:, ok]
            R = self.R[np.ix_(ok, ok)]
            HT = np.swapaxes(H, 1, 2)
            S = H @ P @ HT + R
            keep = ~self._diverged(k, innov, S)
            k, x, P, H, HT, S, innov = (a[keep] for a in (k, x, P, H, HT, S, innov))
            K = np.swapaxes(np.linalg.solve(S, H @ P), 1, 2)
            self.x[k] = x + (K @ innov[..., None])[..., 0]
            IKH = np.eye(x.shape[-1]) - K @ H
            self.P[k] = IKH @ P @ np.swapaxes(IKH, 1, 2) + K @ R @ np.swapaxes(K, 1, 2)
        return self.x.copy()

    def predict(self, u) -> None:
        F = self.system.f_jacobian(self.x, u)
        self.x = self.system.f(self.x, u)
        self.P = F @ self.P @ np.swapaxes(F, 1, 2) + self.Q


class BatchedUKF(_BatchedGaussian):
    """:class:`UnscentedKalmanFilter` over N trajectories."""

    def __init__(self, template: UnscentedKalmanFilter, n: int):
        self.lam, self.Wm, self.Wc = template.lam, template.Wm, template.Wc
        super().__init__(template, n)

    def _sigma_points(self, k: np.ndarray) -> np.ndarray:
        n = self.x.shape[-1]
        try:
            L = np.linalg.cholesky((n + self.lam) * self.P[k])
        except np.linalg.LinAlgError:  # one lost positive definiteness: mend it alone
            L = np.empty_like(self.P[k])
            for j, i in enumerate(k):
                try:
                    L[j] = np.linalg.cholesky((n + self.lam) * self.P[i])
                except np.linalg.LinAlgError:
                    self.P[i] = nearest_covariance(self.P[i])
                    L[j] = np.linalg.cholesky((n + self.lam) * self.P[i])
        x = self.x[k][:, None, :]
        LT = np.swapaxes(L, 1, 2)
        return np.concatenate([x, x + LT, x - LT], axis=1)

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        for k, ok in self.usable_groups(y):
            X = self._sigma_points(k)
            Y = self.system.h(X)[..., ok]
            y_mean = np.einsum("s,nso->no", self.Wm, Y)
            dY = Y - y_mean[:, None, :]
            dX = X - self.x[k][:, None, :]
            S = np.einsum("s,nso,nsp->nop", self.Wc, dY, dY) + self.R[np.ix_(ok, ok)]
            C = np.einsum("s,nsi,nso->nio", self.Wc, dX, dY)
            innov = y[k][:, ok] - y_mean
            keep = ~self._diverged(k, innov, S)
            k, S, C, innov = (a[keep] for a in (k, S, C, innov))
            K = np.swapaxes(np.linalg.solve(S, np.swapaxes(C, 1, 2)), 1, 2)
            self.x[k] = self.x[k] + (K @ innov[..., None])[..., 0]
            P = self.P[k] - K @ S @ np.swapaxes(K, 1, 2)
            self.P[k] = 0.5 * (P + np.swapaxes(P, 1, 2))
        return self.x.copy()

    def predict(self, u) -> None:
        X = self._sigma_points(np.arange(self.n))
        u = np.asarray(u, dtype=float)
        X = self.system.f(X, np.broadcast_to(u[:, None], X.shape[:2]))
        self.x = np.einsum("s,nsi->ni", self.Wm, X)
        dX = X - self.x[:, None, :]
        self.P = np.einsum("s,nsi,nsj->nij", self.Wc, dX, dX) + self.Q


class BatchedParticleFilter(BatchedEstimator):
    """:class:`ParticleFilter` over N trajectories: particles (N, M, n) go through the
    model in one call; copy k draws from its own generator (seeded like the single filter
    of trajectory k), so resampling and noise are the single filter's."""

    def __init__(self, filters: Sequence[ParticleFilter]):
        super().__init__(filters[0], len(filters))
        self.filters = list(filters)
        t = self.template
        self.m = t.n_particles
        self.inv_R = t.inv_R
        self.reset()

    def reset(self, x0=None) -> None:
        for k, f in enumerate(self.filters):
            f.reset(None if x0 is None else np.asarray(x0)[k])
        self.particles = np.stack([f.particles for f in self.filters])
        self.logw = np.zeros((self.n, self.m))

    def _chi2(self, k: np.ndarray, y: np.ndarray, ok: np.ndarray) -> np.ndarray:
        r = self.system.h(self.particles[k])[..., ok] - y[k][:, None, ok]
        return r**2 @ self.inv_R[ok]

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        for k, pattern in self.usable_groups(y):
            chi2 = self._chi2(k, y, pattern)
            lost = chi2.min(axis=1) > self.template.lost_chi2 * pattern.sum()
            for jj in np.flatnonzero(lost):  # sensor resetting, one filter at a time
                i, f = k[jj], self.filters[k[jj]]
                c = max(1, self.m // 10)
                fresh = f.rng.choice(self.m, c, replace=False)
                self.particles[i, fresh] = self.system.sample_domain(f.rng, c)
                self.logw[i, fresh] = self.logw[i].max()
                chi2[jj] = self._chi2(k[jj:jj + 1], y, pattern)[0]
            self.logw[k] = self.logw[k] - 0.5 * chi2
        self.logw -= self.logw.max(axis=1, keepdims=True)
        w = np.exp(self.logw)
        w /= w.sum(axis=1, keepdims=True)
        estimate = np.einsum("nm,nmi->ni", w, self.particles)
        for i in np.flatnonzero(1.0 / np.sum(w**2, axis=1) < 0.5 * self.m):
            self._resample(i, w[i])
        return estimate

    def _resample(self, i: int, w: np.ndarray) -> None:
        f, n = self.filters[i], self.m
        positions = (f.rng.random() + np.arange(n)) / n
        idx = np.minimum(np.searchsorted(np.cumsum(w), positions), n - 1)
        spread = self.particles[i].std(axis=0)
        self.particles[i] = self.particles[i][idx] + f.bandwidth * spread * \
            f.rng.standard_normal((n, self.particles.shape[-1]))
        self.logw[i] = 0.0

    def predict(self, u) -> None:
        std = self.system.process_noise_std
        noise = np.stack([f.rng.standard_normal((self.m, self.particles.shape[-1])) * std
                          for f in self.filters])
        u = np.asarray(u, dtype=float)
        self.particles = self.system.f(self.particles,
                                       np.broadcast_to(u[:, None], (self.n, self.m))) + noise
