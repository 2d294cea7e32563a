"""Common shape of every estimator (KKL, EKF, UKF, particle filter), filterpy style.

At step k the loop calls ``update(y_k)`` (returns the estimate of x_k), the controller
picks ``u_k`` from it, then ``predict(u_k)`` moves the estimator to k+1.

Missing measurements: a component of ``y`` that is NaN or inf, or physically impossible
(outside the system's ``output_low``..``output_high``), never enters the state of an
estimator. The Kalman-type filters and the particle filter skip that component in
the update; the KKL observer replaces it by its own prediction h(x_hat) ("hold the
prediction"), so z keeps moving along the model (see ``docs/observer.md``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from .system import DiscreteSystem


class Estimator(ABC):
    """A recursive state estimator for a :class:`DiscreteSystem`."""

    name: str = "estimator"

    def __init__(self, system: DiscreteSystem):
        self.system = system

    @abstractmethod
    def reset(self, x0: np.ndarray | None = None) -> None:
        """Start again from the initial guess ``x0`` (default: the domain centre)."""

    @abstractmethod
    def update(self, y: np.ndarray) -> np.ndarray:
        """Take the measurement y_k; return the estimate of x_k, shape ``(n_state,)``."""

    @abstractmethod
    def predict(self, u) -> None:
        """Propagate to step k+1 under input u_k."""

    def seed_run(self, seed: int) -> None:  # noqa: B027 (deterministic estimators: no-op)
        """Tie the estimator's own random numbers (if any) to the seed of a run."""

    def initial_guess(self, x0) -> np.ndarray:
        if x0 is None:
            return self.system.domain_center.astype(float).copy()
        return np.asarray(x0, dtype=float).copy()

    def initial_covariance(self) -> np.ndarray:
        """Covariance of a uniform distribution over the training box."""
        return np.diag(self.system.domain_halfwidth**2 / 3.0)


def finite_mask(y: np.ndarray) -> np.ndarray:
    """Which components of ``y`` are finite."""
    return np.isfinite(np.asarray(y, dtype=float))


def usable_mask(system: DiscreteSystem, y: np.ndarray) -> np.ndarray:
    """Which components of ``y`` are usable: finite and physically possible for
    ``system`` (``output_low``..``output_high``). The others are treated as missing."""
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(y)
    if system.output_low is not None:
        ok &= (y >= system.output_low) & (y <= system.output_high)
    return ok


class GaussianFilter(Estimator):
    """Shared state of the Kalman-type filters: mean ``x``, covariance ``P``, and the
    noise covariances Q, R taken from the system."""

    def __init__(self, system: DiscreteSystem, P0: np.ndarray | None = None):
        super().__init__(system)
        self.Q = np.diag(system.process_noise_std**2)
        self.R = np.diag(system.measurement_noise_std**2)
        self.P0 = self.initial_covariance() if P0 is None else np.asarray(P0, dtype=float)
        self.reset()

    def reset(self, x0=None) -> None:
        self.x = self.initial_guess(x0)
        self.P = self.P0.copy()
