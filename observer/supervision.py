"""Is the estimate still explained by the measurements? A consistency monitor.

An estimator can report a confident, wrong x_hat: the KKL's decoder, for instance,
maps any z to some point of its training box, even when the true state left it. The
measurements still tell: the output residual ``y - h(x_hat)`` then stays far above the
noise. :class:`ResidualMonitor` turns that evidence into a "lost" flag that any
estimator (KKL, EKF, UKF, particle filter) can carry, so the loop never acts on an
estimate the data contradict.

The test: an exponential average of the residual (time constant ``tau``) is compared
with its own spread under white noise of the measured level. The noise level is itself
estimated online from successive differences of the powers (``var(y_k - y_{k-1}) =
2 sigma^2`` for a slow signal), so a noisier sensor raises the bar instead of raising
false alarms. The link is also lost when x_hat leaves the domain the estimator knows,
or when no light is seen at all (every power within noise of zero).
"""

from __future__ import annotations

import math

import numpy as np

from .estimator import usable_mask
from .system import DiscreteSystem


class ResidualMonitor:
    """Output-residual consistency test with a noise level learned online.

    Args:
        system: the model whose ``h`` predicts the outputs (``measurement_noise_std``
            gives the initial noise level [W]; ``domain_low``/``domain_high`` the box).
        tau: time constant of the residual average [s] (detection in about 2 tau).
        threshold: squared, normalised averaged residual above which the estimate is
            inconsistent [-] (for white noise alone, chi-square with ``n_output`` degrees
            of freedom: 25 is a false-alarm rate below 1e-5 per step for two).
        domain_margin: share of the domain's half-width x_hat may exceed it by [-].
        noise_tau: time constant of the online noise-level estimate [s].
        model_error: relative error of ``h`` itself (a bias the average does not remove:
            the hull's motion changes the transmitter gain h assumes) [-].
    """

    def __init__(self, system: DiscreteSystem, tau: float = 0.1, threshold: float = 25.0,
                 domain_margin: float = 0.2, noise_tau: float = 1.0,
                 model_error: float = 0.1):
        self.system = system
        self.alpha = min(1.0, system.Te / tau)
        self.noise_alpha = min(1.0, system.Te / noise_tau)
        self.threshold = threshold
        self.model_error = model_error
        half = np.asarray(system.domain_halfwidth, dtype=float)
        self.low = system.domain_center - (1 + domain_margin) * half
        self.high = system.domain_center + (1 + domain_margin) * half
        self.sigma0 = np.asarray(system.measurement_noise_std, dtype=float)
        self.reset()

    def reset(self) -> None:
        """Forget the residual history (after a re-seed); keep the noise level."""
        self.mean_residual = np.zeros(self.system.n_output)
        self.statistic = 0.0
        self.lost = False
        self.reason = ""
        if not hasattr(self, "noise_var"):
            self.noise_var = self.sigma0**2
            self._y_prev = None

    @property
    def noise_std(self) -> np.ndarray:
        """Current estimate of the measurement-noise standard deviation [W]."""
        return np.sqrt(self.noise_var)

    def _learn_noise(self, y: np.ndarray, ok: np.ndarray) -> None:
        prev = self._y_prev
        if prev is not None:
            both = ok & np.isfinite(prev)
            d2 = np.where(both, 0.5 * (y - prev) ** 2, self.noise_var)
            self.noise_var = (1 - self.noise_alpha) * self.noise_var + self.noise_alpha * d2
            self.noise_var = np.maximum(self.noise_var, 0.25 * self.sigma0**2)
        self._y_prev = np.where(ok, y, np.nan)

    def update(self, y: np.ndarray, xhat: np.ndarray) -> bool:
        """Take the measurement y_k and the estimate of x_k; return whether it is lost.

        Missing or impossible samples (see :func:`usable_mask`) leave the residual
        average where it was.
        """
        y = np.asarray(y, dtype=float)
        xhat = np.asarray(xhat, dtype=float)
        ok = usable_mask(self.system, y)
        self._learn_noise(y, ok)
        if not np.all(np.isfinite(xhat)):
            return self._flag(True, "non-finite estimate")
        if np.any(xhat < self.low) or np.any(xhat > self.high):
            return self._flag(True, "estimate outside the domain")
        if not ok.any():
            return self._flag(self.lost, self.reason)
        yhat = np.asarray(self.system.h(xhat), dtype=float)
        a = self.alpha
        r = np.where(ok, y - yhat, 0.0)
        self.mean_residual = np.where(ok, (1 - a) * self.mean_residual + a * r,
                                      self.mean_residual)
        # Allowed: the spread of the average under white noise, plus the model's own bias.
        spread2 = self.noise_var * a / (2 - a) + (self.model_error * yhat) ** 2
        self.statistic = float(np.sum(self.mean_residual**2 / spread2))
        if self.statistic > self.threshold:
            return self._flag(True, "output residual above the noise")
        return self._flag(False, "")

    def _flag(self, lost: bool, reason: str) -> bool:
        self.lost = bool(lost)
        self.reason = reason
        return self.lost



class GainTracker:
    """Online estimate of the link's gain relative to the model's, and the measurements
    rescaled to the model's gain.

    Both photodiodes see one transmitter gain (attenuation, spreading, LED pattern), so
    a change of distance or of the LED's emission angle scales the two powers together:
    ``y = ratio * h(x)``, while the shape of the pair (P1 / P2) depends on phi alone.

    The powers, first averaged over ``tau_powers`` (so the noise does not bias the
    nonlinear inversion), are inverted for the gain through the shape
    (``shape_inverse``, supplied by the caller, who knows the receiver). A Kalman filter
    on log(ratio) and its rate (the rate a random walk of ``drift``) weighs each
    inversion by its variance: off the intensity peak the two photodiodes see nearly the same
    log-slope and the gain is barely determined, at the peak it is well determined.

    The estimator sees ``y / ratio``. ``ratio`` moves only when the filter's estimate
    leaves a band of ``deadband`` (relative) or four posterior standard deviations
    around it: near the peak a gain error eps reads as an angle error, so the filter's
    own jitter must not reach the estimator while the gain holds. The fit never uses
    the estimate, so a wrong estimate cannot drag the gain with it.

    Args:
        system: the estimator's model (its ``h`` defines ratio = 1).
        shape_inverse: ``shape_inverse(y) -> (phi, gain, v)`` for one pair of powers
            [W]: the gain in the units of ``model_gain`` and the variance ``v`` of the
            relative gain per unit noise variance [1/W^2].
        model_gain: the gain of the model's ``h`` in those units.
        drift: random walk of the rate of log(ratio) [1/s^1.5].
        ratio: initial ratio (for example the configured distance's gain over the
            model's) [-].
        min_snr: both averaged powers must exceed this many noise standard deviations.
        tau_powers: time constant of the average of the powers before inversion [s].
        deadband: smallest relative change passed on to ``ratio`` [-] while the gain
            holds still or wobbles.
        deadband_moving: the same while the filter sees a significant trend [-].
        max_std: samples whose log-gain standard deviation exceeds this are not used.
    """

    def __init__(self, system: DiscreteSystem, shape_inverse, model_gain: float,
                 drift: float = 0.05, ratio: float = 1.0, min_snr: float = 5.0,
                 tau_powers: float = 0.1, deadband: float = 0.05,
                 deadband_moving: float = 0.005, max_std: float = 0.1):
        self.system = system
        self.shape_inverse = shape_inverse
        self.model_gain = float(model_gain)
        Te = system.Te
        # Constant-rate model of log(ratio): a ramp (a drifting transmitter, a turning
        # hull) is followed without lag, while the rate itself changes slowly, so a
        # gain that only wobbles (hull vibration) is averaged out.
        self.F = np.array([[1.0, Te], [0.0, 1.0]])
        self.Q = drift**2 * np.array([[Te**3 / 3, Te**2 / 2], [Te**2 / 2, Te]])
        self.deadband = deadband
        self.deadband_moving = deadband_moving
        self.max_variance = max_std**2
        self.alpha_powers = min(1.0, system.Te / tau_powers)
        self.min_power = min_snr * np.asarray(system.measurement_noise_std, dtype=float)
        self.set(ratio, variance=0.0)

    def normalize(self, y: np.ndarray) -> np.ndarray:
        """The measurement in the model's gain: ``y / ratio``."""
        return np.asarray(y, dtype=float) / self.ratio

    @property
    def estimate(self) -> float:
        """The filter's current ratio [-] (``ratio`` is what the estimator sees)."""
        return math.exp(self.state[0])

    def update(self, y: np.ndarray, noise_std: np.ndarray | None = None) -> None:
        """Learn from one sample of raw powers ``y`` [W] (``noise_std``: the measured
        noise level [W], default the model's scaled by the ratio)."""
        y = np.asarray(y, dtype=float)
        self.state = self.F @ self.state
        self.P = self.F @ self.P @ self.F.T + self.Q
        if not np.all(np.isfinite(y)):
            return
        sigma = np.asarray(self.system.measurement_noise_std * self.ratio
                           if noise_std is None else noise_std, dtype=float)
        a = self.alpha_powers
        self.powers = y.copy() if self.powers is None else (1 - a) * self.powers + a * y
        if not np.all(self.powers > self.min_power / self.system.measurement_noise_std
                      * sigma):
            return
        _, gain, v = self.shape_inverse(self.powers)
        if not (math.isfinite(gain) and gain > 0 and math.isfinite(v)):
            return
        r = v * float(np.mean(sigma**2))  # variance of log(gain) from one sample
        if r > self.max_variance:  # far off the peak: the pair barely fixes the gain
            return
        P = self.P
        k = P[:, 0] / (P[0, 0] + r)
        self.state = self.state + k * (math.log(gain / self.model_gain) - self.state[0])
        self.P = P - np.outer(k, P[0])
        # A significant trend (a drift, not a wobble) is followed closely.
        moving = abs(self.state[1]) > 3 * math.sqrt(self.P[1, 1])
        est, band = self.estimate, self.deadband_moving if moving else self.deadband
        self.ratio = min(max(self.ratio, est / (1 + band)), est / (1 - band))

    def set(self, ratio: float, variance: float = 1e-4) -> None:
        """Restart from ``ratio`` [-], no trend, variance ``variance`` of its log."""
        if math.isfinite(ratio) and ratio > 0:
            self.ratio = float(ratio)
            self.state = np.array([math.log(ratio), 0.0])
            self.P = np.diag([variance, 0.01])
            self.powers = None
