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

from observer import jit
from observer.estimator import usable_mask
from observer.system import DiscreteSystem

compiled_monitor = jit.lazy("observer.supervision.compiled_monitor")


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
        domain_tau: time constant of the average of x_hat that the domain test reads
            [s]: an estimate that runs away leaves the box on average within a few
            steps, one that a noisy sample throws out for a step or two does not (under
            moderate scintillation a noisy KKL's phidot crossed the box's edge for a
            step every few seconds, each a loss).
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
                 dark_sigmas: float = 3.0, dark_time: float = 0.2,
                 domain_tau: float = 0.03):
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
        self.domain_alpha = min(1.0, system.Te / domain_tau)
        # The compiled path (observer/supervision/compiled_monitor.py), chosen once: a
        # model that gives its h as numbers, and its state in arrays.
        h = getattr(system, "compiled_h", None)
        self._kernel = h() if h is not None and jit.enabled() else None
        if self._kernel is not None:
            low, high = system.output_low, system.output_high
            n = system.n_output
            self._kernel += (np.zeros(n) if low is None else np.asarray(low, dtype=float),
                             np.zeros(n) if high is None else np.asarray(high, dtype=float),
                             low is not None, self.low.astype(float), self.high.astype(float),
                             np.asarray(self._noise_floor))
            # y_prev, the averaged estimate, the ring of brightest powers, the counters
            self._arrays = (np.full(n, np.nan), np.zeros(system.n_state),
                            np.zeros(self.dark_steps), np.zeros(5))
        self.reset()

    def reset(self) -> None:
        """Forget the residual history (after a re-seed); keep the noise level."""
        if self._kernel is not None:
            self._compiled_reset()
            return
        self._mean_residual = [0.0] * self.system.n_output
        self.statistic = 0.0
        self.lost = False
        self.reason = ""
        self._bright: list[float] = []  # the brightest usable power of recent steps
        self._mean_x: list[float] | None = None  # the averaged estimate (domain test)
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
        values = [float(v) for v in np.broadcast_to(value, self.sigma0.shape)]
        if self._kernel is not None:  # the compiled path's array, in place
            self._noise_var[:] = values
        else:
            self._noise_var = values

    def update(self, y: np.ndarray, xhat: np.ndarray) -> bool:
        """Take the measurement y_k and the estimate of x_k; return whether it is lost.

        Missing or impossible samples (see :func:`usable_mask`) leave the residual
        average where it was.
        """
        if self._kernel is not None:
            return self._compiled_update(y, xhat)
        ok = usable_mask(self.system, y).tolist()
        y = np.asarray(y, dtype=float).tolist()
        xh = np.asarray(xhat, dtype=float).tolist()
        self._learn_noise(y, ok)
        if not all(math.isfinite(v) for v in xh):
            return self._flag(True, "non-finite estimate")
        if self._mean_x is None:
            self._mean_x = list(xh)
        else:
            b = self.domain_alpha
            self._mean_x = [(1 - b) * m + b * v for m, v in zip(self._mean_x, xh, strict=True)]
        if any(v < lo or v > hi for v, lo, hi in zip(self._mean_x, self._low, self._high,
                                                       strict=True)):
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

    def _compiled_reset(self) -> None:
        """:meth:`reset` of the compiled path's arrays."""
        if not hasattr(self, "_noise_var"):
            self._noise_var = np.zeros(self.system.n_output)
            self.noise_var = self.sigma0**2 * self.noise_ratio**2
        self._mean_residual = np.zeros(self.system.n_output)
        self.statistic, self.lost, self.reason = 0.0, False, ""
        counters = self._arrays[-1]
        counters[1:] = 0.0  # the averaged estimate, the ring of powers, the statistic

    def _compiled_update(self, y, xhat) -> bool:
        """:meth:`update` in one compiled call."""
        code = compiled_monitor.update(
            np.asarray(y, dtype=float), np.asarray(xhat, dtype=float), *self._kernel,
            self._mean_residual, self._noise_var, *self._arrays, self.alpha,
            self.noise_alpha, self.domain_alpha, self.threshold, self.model_error,
            self.dark_sigmas)
        self.statistic = float(self._arrays[-1][4])
        reason = compiled_monitor.REASONS[code]
        if reason is None:  # no usable sample: the last decision stands
            return self.lost
        return self._flag(code != 0, reason)

    @property
    def mean_residual(self) -> np.ndarray:
        """Exponential average of the output residual y - h(x_hat) [W]."""
        return np.array(self._mean_residual)

    def _flag(self, lost: bool, reason: str) -> bool:
        self.lost = bool(lost)
        self.reason = reason
        return self.lost
