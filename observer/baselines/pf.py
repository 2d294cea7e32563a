"""Bootstrap particle filter: with enough particles, a stand-in for the Bayesian optimum."""

from __future__ import annotations

import numpy as np

from observer.estimator import Estimator, ToldNoise, usable_mask
from observer.exceptions import ObserverError
from observer.system import DiscreteSystem


class ParticleFilter(ToldNoise, Estimator):
    """Sequential importance resampling with systematic resampling and regularisation.

    Args:
        system: plant; its noise levels give the process noise and the likelihood.
        n_particles: number of particles.
        P0: covariance of the Gaussian initial cloud (default: uniform law on the domain).
        seed: seed of the filter's own random numbers.
        jitter: after a resampling, add Gaussian noise of ``jitter`` x the Silverman
            bandwidth times the cloud's spread, against sample impoverishment.
        lost_chi2: when even the best particle's chi-square per usable output exceeds
            this, the cloud has lost the state (after a stream of garbage, say): a tenth
            of the particles is redrawn uniformly over the domain ("sensor resetting").
            With 2000 particles this never happens on valid data.
    """

    name = "pf"
    #: A run with seed s draws the filter's numbers from SEED_OFFSET + s, apart from the
    #: run's noise seeds.
    SEED_OFFSET = 10_000

    def __init__(self, system: DiscreteSystem, n_particles: int = 5000,
                 P0: np.ndarray | None = None, seed: int = 0, jitter: float = 0.5,
                 lost_chi2: float = 25.0):
        super().__init__(system)
        if n_particles < 1:
            raise ObserverError(f"n_particles={n_particles}: must be >= 1")
        self.n_particles = n_particles
        self.P0 = self.initial_covariance() if P0 is None else np.asarray(P0, dtype=float)
        self.seed = seed
        self.jitter = jitter
        self.lost_chi2 = lost_chi2
        self.inv_R = 1.0 / system.measurement_noise_std**2
        self._log_var = None
        d = system.n_state
        self.bandwidth = jitter * (4.0 / (n_particles * (d + 2))) ** (1.0 / (d + 4))
        self.reset()

    def seed_run(self, seed: int) -> None:
        self.seed = self.SEED_OFFSET + seed

    def reset(self, x0=None, covariance=None) -> None:
        self.rng = np.random.default_rng(self.seed)
        L = np.linalg.cholesky(self.P0 if covariance is None else
                               np.asarray(covariance, dtype=float))
        self.particles = self.initial_guess(x0) + self.rng.standard_normal(
            (self.n_particles, self.system.n_state)) @ L.T
        self.logw = np.zeros(self.n_particles)

    def covariance(self) -> np.ndarray:
        """The weighted covariance of the particles."""
        w = np.exp(self.logw - self.logw.max())
        w /= w.sum()
        d = self.particles - w @ self.particles
        return (w[:, None] * d).T @ d

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        ok = usable_mask(self.system, y)
        if ok.any():
            chi2 = self._chi2(y, ok)
            if chi2.min() > self.lost_chi2 * ok.sum():
                k = max(1, self.n_particles // 10)
                fresh = self.rng.choice(self.n_particles, k, replace=False)
                self.particles[fresh] = self.system.sample_domain(self.rng, k)
                self.logw[fresh] = self.logw.max()
                chi2 = self._chi2(y, ok)
            if self._log_var is not None:
                chi2 = chi2 + self._log_var
            self.logw = self.logw - 0.5 * chi2
        self.logw -= self.logw.max()
        w = np.exp(self.logw)
        w /= w.sum()
        estimate = w @ self.particles
        if 1.0 / np.sum(w**2) < 0.5 * self.n_particles:
            self._resample(w)
        return estimate

    def _chi2(self, y, ok) -> np.ndarray:
        chi2 = self._model_chi2(y, ok)
        return chi2 if self.noise_scale == 1.0 else chi2 / (self.noise_scale ** 2)

    def _model_chi2(self, y, ok) -> np.ndarray:
        """The normalised squared residual r^2 / var of ``y`` per particle (each
        particle's own R where the noise depends on the output; then
        ``self._log_var`` keeps the log-determinants the likelihood adds)."""
        h = self.system.h(self.particles)
        r = h[:, ok] - y[ok]
        noise = self.system.measurement_noise
        if noise is None or not noise.signal_dependent:
            return r**2 @ self.inv_R[ok]
        var = noise.std_at(h[:, ok]) ** 2 * self.inv_R[ok]  # over the floor's
        self._log_var = np.sum(np.log(var), axis=1)
        return np.sum(r**2 * self.inv_R[ok] / var, axis=1)

    def _resample(self, w) -> None:
        n = self.n_particles
        positions = (self.rng.random() + np.arange(n)) / n
        idx = np.minimum(np.searchsorted(np.cumsum(w), positions), n - 1)
        spread = self.particles.std(axis=0)
        self.particles = self.particles[idx] + self.bandwidth * spread * \
            self.rng.standard_normal(self.particles.shape)
        self.logw = np.zeros(n)

    def predict(self, u) -> None:
        noise = self.rng.standard_normal(self.particles.shape) * self.system.process_noise_std
        self.particles = self.system.f(self.particles, u) + noise
