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
        noise_ratio: the initial noise level over the system's nominal one [-].
        dark_sigmas, dark_time: no light is seen when the brightest usable power,
            averaged over the last ``dark_time`` [s], is within ``dark_sigmas`` standard
            deviations of that average's noise of zero (averaging lets a weak but steady
            link, a few noise levels bright, count as light).
    """

    def __init__(self, system: DiscreteSystem, tau: float = 0.1, threshold: float = 25.0,
                 domain_margin: float = 0.2, noise_tau: float = 1.0,
                 model_error: float = 0.1, noise_ratio: float = 1.0,
                 dark_sigmas: float = 3.0, dark_time: float = 0.2):
        self.system = system
        self.alpha = min(1.0, system.Te / tau)
        self.noise_alpha = min(1.0, system.Te / noise_tau)
        self.threshold = threshold
        self.model_error = model_error
        half = np.asarray(system.domain_halfwidth, dtype=float)
        self.low = system.domain_center - (1 + domain_margin) * half
        self.high = system.domain_center + (1 + domain_margin) * half
        self._low, self._high = self.low.tolist(), self.high.tolist()
        self.sigma0 = np.asarray(system.measurement_noise_std, dtype=float)
        self._noise_floor = (0.25 * self.sigma0**2).tolist()
        self.noise_ratio = noise_ratio
        self.dark_sigmas = dark_sigmas
        self.dark_steps = max(1, int(round(dark_time / system.Te)))
        self.reset()

    def reset(self) -> None:
        """Forget the residual history (after a re-seed); keep the noise level."""
        self._mean_residual = [0.0] * self.system.n_output
        self.statistic = 0.0
        self.lost = False
        self.reason = ""
        self._bright: list[float] = []  # the brightest usable power of recent steps
        if not hasattr(self, "_noise_var"):
            self.noise_var = self.sigma0**2 * self.noise_ratio**2
            self._y_prev = None

    @property
    def noise_std(self) -> np.ndarray:
        """Current estimate of the measurement-noise standard deviation [W]."""
        return np.sqrt(self.noise_var)

    def _learn_noise(self, y: list, ok: list) -> None:
        # Plain floats: two outputs, and numpy's per-call overhead dominated the loop.
        prev, var, a = self._y_prev, self._noise_var, self.noise_alpha
        if prev is not None:
            floor = self._noise_floor
            for i, (yi, pi) in enumerate(zip(y, prev, strict=True)):
                d2 = 0.5 * (yi - pi) ** 2 if ok[i] and math.isfinite(pi) else var[i]
                var[i] = max((1 - a) * var[i] + a * d2, floor[i])
        self._y_prev = [yi if oki else math.nan for yi, oki in zip(y, ok, strict=True)]

    @property
    def noise_var(self) -> np.ndarray:
        """Current estimate of the measurement-noise variance [W^2]."""
        return np.array(self._noise_var)

    @noise_var.setter
    def noise_var(self, value) -> None:
        self._noise_var = [float(v) for v in np.broadcast_to(value, self.sigma0.shape)]

    def update(self, y: np.ndarray, xhat: np.ndarray) -> bool:
        """Take the measurement y_k and the estimate of x_k; return whether it is lost.

        Missing or impossible samples (see :func:`usable_mask`) leave the residual
        average where it was.
        """
        ok = usable_mask(self.system, y).tolist()
        y = np.asarray(y, dtype=float).tolist()
        xh = np.asarray(xhat, dtype=float).tolist()
        self._learn_noise(y, ok)
        if not all(math.isfinite(v) for v in xh):
            return self._flag(True, "non-finite estimate")
        if any(v < lo or v > hi for v, lo, hi in zip(xh, self._low, self._high, strict=True)):
            return self._flag(True, "estimate outside the domain")
        if not any(ok):
            return self._flag(self.lost, self.reason)
        yhat = np.asarray(self.system.h(np.asarray(xhat, dtype=float)), dtype=float).tolist()
        a, m, statistic = self.alpha, self._mean_residual, 0.0
        for i, (yi, yhi) in enumerate(zip(y, yhat, strict=True)):
            if ok[i]:
                m[i] = (1 - a) * m[i] + a * (yi - yhi)
            # Allowed: the spread of the average under white noise, plus the model's bias.
            spread2 = self._noise_var[i] * a / (2 - a) + (self.model_error * yhi) ** 2
            statistic += m[i] ** 2 / spread2
        self.statistic = statistic
        if self.statistic > self.threshold:
            return self._flag(True, "output residual above the noise")
        if self._no_light(y, ok):
            return self._flag(True, "no light")
        return self._flag(False, "")

    def _no_light(self, y: list, ok: list) -> bool:
        """The brightest usable power, averaged over the last ``dark_time``, is within
        ``dark_sigmas`` of its noise of zero."""
        bright = self._bright
        bright.append(max(v for v, o in zip(y, ok, strict=True) if o))
        if len(bright) > self.dark_steps:
            del bright[0]
        n = len(bright)
        return n == self.dark_steps and sum(bright) / n <= \
            self.dark_sigmas * math.sqrt(max(self._noise_var) / n)

    @property
    def mean_residual(self) -> np.ndarray:
        """Exponential average of the output residual y - h(x_hat) [W]."""
        return np.array(self._mean_residual)

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
    leaves a band of ``deadband`` (relative) around it: near the peak a gain error eps
    reads as an angle error, so the filter's own jitter must not reach the estimator
    while the gain holds. The fit never uses the estimate, so a wrong estimate cannot
    drag the gain with it.

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
            holds still or wobbles (at 0.05, a hull 2 mm off station left the KKL 4.5%
            of gain it could not explain, and its estimate went over the peak; at 0.02
            a gain error inside the band still biased every estimator's phi by up to
            c1 sqrt(0.02) = 0.04 rad near the peak: 0.005 halved the KKL's and the
            EKF's steady phi RMSE, ``docs/bound.md``).
        deadband_moving: the same while the filter sees a trend [-].
        max_std: samples whose log-gain standard deviation exceeds this are not used
            (at 0.1 it went blind 0.06 rad off the peak at d = 0.15 m: 9% gain drift).
    """

    def __init__(self, system: DiscreteSystem, shape_inverse, model_gain: float,
                 drift: float = 0.05, ratio: float = 1.0, min_snr: float = 5.0,
                 tau_powers: float = 0.1, deadband: float = 0.005,
                 deadband_moving: float = 0.005, max_std: float = 0.3):
        self.system = system
        self.shape_inverse = shape_inverse
        self.model_gain = float(model_gain)
        Te = system.Te
        # Constant-rate model of log(ratio): a ramp (a drifting transmitter, a turning
        # hull) is followed without lag, while the rate itself changes slowly, so a
        # gain that only wobbles (hull vibration) is averaged out. Two states: plain
        # floats (numpy's per-call cost dominated the loop).
        self.Te = Te
        q = drift**2
        self._Q = (q * Te**3 / 3, q * Te**2 / 2, q * Te)  # (00, 01, 11)
        self.deadband = deadband
        self.deadband_moving = deadband_moving
        self.max_variance = max_std**2
        self.alpha_powers = min(1.0, system.Te / tau_powers)
        self._nominal_sigma = np.asarray(system.measurement_noise_std, dtype=float).tolist()
        self._min_snr = float(min_snr)
        self.set(ratio, variance=0.0)

    @property
    def state(self) -> np.ndarray:
        """(log ratio [-], its rate [1/s])."""
        return np.array(self._s)

    @property
    def P(self) -> np.ndarray:
        """Covariance of :attr:`state`."""
        p00, p01, p11 = self._P
        return np.array([[p00, p01], [p01, p11]])

    def normalize(self, y: np.ndarray) -> np.ndarray:
        """The measurement in the model's gain: ``y / ratio``."""
        return np.asarray(y, dtype=float) / self.ratio

    @property
    def estimate(self) -> float:
        """The filter's current ratio [-] (``ratio`` is what the estimator sees)."""
        return math.exp(self._s[0])

    def update(self, y: np.ndarray, noise_std: np.ndarray | None = None) -> None:
        """Learn from one sample of raw powers ``y`` [W] (``noise_std``: the measured
        noise level [W], default the model's scaled by the ratio)."""
        Te, (q00, q01, q11) = self.Te, self._Q
        s0, s1 = self._s
        p00, p01, p11 = self._P
        s0 += Te * s1
        p00, p01 = p00 + 2 * Te * p01 + Te * Te * p11 + q00, p01 + Te * p11 + q01
        p11 += q11
        self._s, self._P = (s0, s1), (p00, p01, p11)
        y = np.asarray(y, dtype=float).tolist()
        if not all(math.isfinite(v) for v in y):
            return
        sigma = ([v * self.ratio for v in self._nominal_sigma] if noise_std is None
                 else np.asarray(noise_std, dtype=float).tolist())
        a = self.alpha_powers
        self._powers = list(y) if self._powers is None else \
            [(1 - a) * pw + a * v for pw, v in zip(self._powers, y, strict=True)]
        if not all(pw > self._min_snr * sg for pw, sg in zip(self._powers, sigma,
                                                               strict=True)):
            return
        _, gain, v = self.shape_inverse(self._powers)
        if not (math.isfinite(gain) and gain > 0 and math.isfinite(v)):
            return
        r = v * sum(sg * sg for sg in sigma) / len(sigma)  # variance of log(gain), 1 sample
        if r > self.max_variance:  # far off the peak: the pair barely fixes the gain
            return
        k0, k1 = p00 / (p00 + r), p01 / (p00 + r)
        innovation = math.log(gain / self.model_gain) - s0
        self._s = (s0 + k0 * innovation, s1 + k1 * innovation)
        self._P = (p00 - k0 * p00, p01 - k0 * p01, p11 - k1 * p01)
        # A significant trend (a drift, not a wobble) is followed closely.
        moving = abs(self._s[1]) > 3 * math.sqrt(self._P[2])
        est, band = self.estimate, self.deadband_moving if moving else self.deadband
        self.ratio = min(max(self.ratio, est / (1 + band)), est / (1 - band))

    @property
    def powers(self) -> np.ndarray | None:
        """The averaged powers the gain is inverted from [W] (None before any)."""
        return None if self._powers is None else np.array(self._powers)

    def refit(self, ratio: float, variance: float = 1e-4) -> None:
        """Restart the filter from a fit's ``ratio`` [-] (a re-seed's), passed on to
        :attr:`ratio` only as far as it leaves the deadband (the rule of :meth:`update`):
        a fit of a few samples is noisier than the band."""
        seen = self.ratio
        self.set(ratio, variance)
        if math.isfinite(ratio) and ratio > 0:
            self.ratio = min(max(seen, ratio / (1 + self.deadband)),
                             ratio / (1 - self.deadband))

    def set(self, ratio: float, variance: float = 1e-4) -> None:
        """Restart from ``ratio`` [-], no trend, variance ``variance`` of its log."""
        if math.isfinite(ratio) and ratio > 0:
            self.ratio = float(ratio)
            self._s = (math.log(ratio), 0.0)
            self._P = (float(variance), 0.0, 0.01)
            self._powers = None
