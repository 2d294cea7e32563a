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

import math
from abc import ABC, abstractmethod

import numpy as np

from observer.system import DiscreteSystem


class Estimator(ABC):
    """A recursive state estimator for a :class:`DiscreteSystem`."""

    name: str = "estimator"
    #: Whether its supervisor tells it the channel's factor on the sensor's noise
    #: (a Bayesian filter, whose model holds the sensor's noise) instead of the noise over
    #: the model's nominal (:meth:`adapt_noise`).
    models_its_noise: bool = False
    #: Whether the last estimate, or the state the last input drove the model to
    #: (f(x_hat, u), what the input correction encodes), lies outside the system's
    #: training box: a learned observer's maps then extrapolate. Only the KKL family
    #: has maps to leave; the filters' stays False.
    outside_domain: bool = False

    def __init__(self, system: DiscreteSystem):
        self.system = system
        # The training box as plain floats: in_domain runs twice a step.
        self._box = list(zip(np.asarray(system.domain_low, dtype=float).tolist(),
                             np.asarray(system.domain_high, dtype=float).tolist(),
                             strict=True))

    def in_domain(self, x) -> bool:
        """Whether the state ``x`` (n_state,) lies inside the system's training box."""
        return all(lo <= v <= hi for v, (lo, hi) in zip(
            np.asarray(x, dtype=float).tolist(), self._box, strict=True))

    @abstractmethod
    def reset(self, x0: np.ndarray | None = None,
              covariance: np.ndarray | None = None) -> None:
        """Start again from the initial guess ``x0`` (default: the domain centre).

        ``covariance``: how sure that guess is, shape ``(n_state, n_state)`` in the
        state's units squared (None: the estimator's own initial uncertainty). A
        Bayesian filter starts from it; an observer without a covariance (the KKL)
        ignores it."""

    @abstractmethod
    def update(self, y: np.ndarray) -> np.ndarray:
        """Take the measurement y_k; return the estimate of x_k, shape ``(n_state,)``."""

    @abstractmethod
    def predict(self, u) -> None:
        """Propagate to step k+1 under input u_k."""

    def seed_run(self, seed: int) -> None:  # noqa: B027 (deterministic estimators: no-op)
        """Tie the estimator's own random numbers (if any) to the seed of a run."""

    def adapt_noise(self, noise_ratio: float, y: np.ndarray | None = None
                    ) -> np.ndarray | None:
        """The measurement noise the powers now carry, over the model's nominal [-]: an
        estimator that adapts to it does (a bank picks its member, a gain-scheduled KKL
        sets its floor); ``y`` is the step's measurement (None: before the run, where a
        bank starts on its member at once). Returns the new estimate when adapting
        changed it, else None. An estimator that :attr:`models_its_noise` is told the
        channel's factor on the sensor's noise instead (:class:`ToldNoise`)."""
        return None

    def covariance(self) -> np.ndarray | None:
        """How sure the last estimate is: its covariance ``(n_state, n_state)`` in the
        state's units squared, or None for an estimator without one (the KKL). Not to be
        modified."""
        return None

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


class ToldNoise:
    """The measurement noise of a Bayesian filter, over its model's. Its model holds
    the sensor's noise (signal-dependent shot noise included), at the noise scale the
    run tells it (:meth:`tell_noise_scale`); what its supervisor tells it is only what
    the channel adds to that (:meth:`adapt_noise`: a fading channel's share)."""

    #: The supervisor tells it the channel's factor on the sensor's noise, not the
    #: noise over the model's nominal (:meth:`Estimator.adapt_noise`).
    models_its_noise = True
    noise_scale: float = 1.0  # the measurement noise over the model's [-]
    _base_scale: float = 1.0

    def tell_noise_scale(self, scale: float) -> None:
        """The run's measurement noise is ``scale`` times the model's [-]."""
        self._base_scale = self.noise_scale = float(scale)

    def adapt_noise(self, noise_ratio: float, y: np.ndarray | None = None) -> None:
        """The channel's noise is ``noise_ratio`` times the sensor's [-] (1: no fading);
        the estimate stays."""
        ratio = float(noise_ratio)
        if math.isfinite(ratio) and ratio > 0:
            self.noise_scale = self._base_scale * ratio
        return None


class GaussianFilter(ToldNoise, Estimator):
    """Shared state of the Kalman-type filters: mean ``x``, covariance ``P``, and the
    noise covariances Q, R taken from the system.

    Divergence: a Kalman filter driven far off (by a stream of garbage, say) can sit
    where h is flat and never come back. When the normalised innovation squared stays
    above ``lost_nis`` per usable output for ``lost_steps`` steps in a row, the filter
    starts again from the domain centre with P0 (from where it converges)."""

    def __init__(self, system: DiscreteSystem, P0: np.ndarray | None = None,
                 lost_nis: float = 25.0, lost_steps: int = 50):
        super().__init__(system)
        self.Q = np.diag(system.process_noise_std**2)
        self.R = np.diag(system.measurement_noise_std**2)
        noise = system.measurement_noise
        #: The noise depends on the output (a physical receiver): R is taken at the
        #: predicted output each update (:meth:`R_at`).
        self.signal_noise = noise is not None and noise.signal_dependent
        #: The system states the relative error of its h (:meth:`R_at` counts it).
        self.counts_model_error = bool(getattr(system, "model_error", 0.0))
        self.P0 = self.initial_covariance() if P0 is None else np.asarray(P0, dtype=float)
        self.lost_nis, self.lost_steps = lost_nis, lost_steps
        self.reset()

    def R_at(self, y_pred: np.ndarray | None, ok: np.ndarray) -> np.ndarray:
        """R over the usable outputs ``ok`` at the predicted output ``y_pred`` (needed
        only where the noise depends on the output, or where the system states the
        relative error of its own h, ``model_error``: its share of each output adds to
        the noise, so that a filter at a high SNR does not trust h beyond its
        accuracy)."""
        R = self.system.measurement_noise.covariance(y_pred) if self.signal_noise else self.R
        R = R[np.ix_(ok, ok)]
        error = getattr(self.system, "model_error", 0.0)
        if error and y_pred is not None:
            R = R + np.diag((error * np.asarray(y_pred)[ok]) ** 2)
        return R if self.noise_scale == 1.0 else R * (self.noise_scale * self.noise_scale)

    def covariance(self) -> np.ndarray:
        return self.P

    def reset(self, x0=None, covariance=None) -> None:
        self.x = self.initial_guess(x0)
        self.P = (self.P0 if covariance is None else np.asarray(covariance, dtype=float)).copy()
        self.inconsistent = 0  # steps in a row with an implausible innovation

    #: How far outside its domain (in half-widths from the centre) the mean may go
    #: before the filter starts again: only a run-away, never a real excursion.
    CONTAINED_WIDTHS = 100.0

    def contain(self) -> None:
        """Start again from the domain's centre when the mean ran away: a prediction
        without updates (a gated sample, a lost link) through a nonlinear f can square
        a bad estimate step after step (1e2, 1e4, 1e8, ...) until it overflows."""
        box = self.contain_box()
        # NaN fails every comparison, and a non-finite P makes its sum non-finite
        if not (all(lo <= v <= hi for v, (lo, hi) in zip(self.x.tolist(), box, strict=True))
                and math.isfinite(float(self.P.sum()))):
            self.reset()

    def contain_box(self) -> list[tuple[float, float]]:
        """Each state's (low, high) bounds the mean may not leave (:meth:`contain`), in
        plain floats: numpy's per-call cost was 5 % of an EKF step."""
        box = getattr(self, "_contained_box", None)
        if box is None:
            s, k = self.system, self.CONTAINED_WIDTHS
            box = self._contained_box = [
                (0.5 * (lo + hi) - k * 0.5 * (hi - lo), 0.5 * (lo + hi) + k * 0.5 * (hi - lo))
                for lo, hi in zip(s.domain_low.tolist(), s.domain_high.tolist(), strict=True)]
        return box

    def diverged(self, innov: np.ndarray, S: np.ndarray) -> bool:
        """Count an implausible innovation; True (and a fresh start) once too many
        came in a row."""
        nis = float(innov @ np.linalg.solve(S, innov))
        self.inconsistent = self.inconsistent + 1 if nis > self.lost_nis * innov.size else 0
        if self.inconsistent < self.lost_steps:
            return False
        self.reset()
        return True
