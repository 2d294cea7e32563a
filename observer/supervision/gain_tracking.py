"""The link's gain, tracked through a physical invariant: both photodiodes see one
transmitter gain, so its changes (distance, attenuation, the LED's angle) scale the pair
together, while the pair's shape depends on phi alone."""

from __future__ import annotations

import math

import numpy as np

from observer import jit
from observer.supervision.fading import FadingChannel
from observer.system import DiscreteSystem

compiled_gain = jit.lazy("observer.supervision.compiled_gain")


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

    A fading channel (scintillation) scales both powers together too, but sample by
    sample, faster than any filter of the gain can follow: each sample is also taken on
    its own (:meth:`sample`) by a :class:`~observer.supervision.fading.FadingChannel`, which learns
    the fading and divides it out of the sample's common scale (``fade``).

    The estimator sees ``y / ratio`` (divided by the sample's fade when one is
    learned). ``ratio`` moves only when the filter's estimate
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
        fade_time, phi_variance: the :class:`~observer.supervision.fading.FadingChannel`'s.
        shape: the receiver's pair as numbers, for the compiled path
            (:mod:`observer.supervision.compiled_pair`; None: the reference only).
    """

    def __init__(self, system: DiscreteSystem, shape_inverse, model_gain: float,
                 drift: float = 0.05, ratio: float = 1.0, min_snr: float = 5.0,
                 tau_powers: float = 0.1, deadband: float = 0.005,
                 deadband_moving: float = 0.005, max_std: float = 0.3,
                 fade_time: float = 1.0, phi_variance=None, shape: tuple | None = None):
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
        self._sigma: list | None = None  # the last noise level update() was given [W]
        self.shape = shape
        self.channel = FadingChannel(Te, shape_inverse, self.model_gain, phi_variance,
                                     min_snr, fade_time, shape=shape)
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
        """The measurement in the model's gain: ``y / ratio``, and divided by the fade of
        the step's sample (:meth:`sample`) while the channel fades."""
        if self.fade == 1.0:
            return np.asarray(y, dtype=float) / self.ratio
        return np.asarray(y, dtype=float) / (self.ratio * self.fade)

    @property
    def fade(self) -> float:
        """This step's sample's fade [-] (1: none learned): :class:`FadingChannel`."""
        return self.channel.fade

    def sample(self, y: np.ndarray, q: float | None = None,
               noise_std: float | None = None) -> float:
        """Take this step's raw powers ``y`` [W] before :meth:`normalize`, at encoder
        angle ``q`` [rad] in the line of sight's frame (None: unknown), with the sensor's
        own noise ``noise_std`` [W] (None: the last :meth:`update`'s level): the channel
        learns from it and sets its fade (:meth:`FadingChannel.sample`). Returns the
        fade [-]."""
        if noise_std is not None:
            sigma = [float(noise_std)] * len(y)
        else:
            sigma = self._sigma or [v * self.ratio for v in self._nominal_sigma]
        return self.channel.sample(y, q, sigma, self.ratio)

    @property
    def estimate(self) -> float:
        """The filter's current ratio [-] (``ratio`` is what the estimator sees)."""
        return math.exp(self._s[0])

    def update(self, y: np.ndarray, noise_std: np.ndarray | None = None) -> None:
        """Learn from one sample of raw powers ``y`` [W] (``noise_std``: the measured
        noise level [W], default the model's scaled by the ratio)."""
        if self.shape is not None and jit.enabled():
            self._compiled_update(y, noise_std)
            return
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
        self._sigma = sigma
        a = self.alpha_powers
        if self._powers is None:
            self._powers, self._lag = list(y), 0.0
        else:
            self._powers = [(1 - a) * pw + a * v for pw, v in zip(self._powers, y, strict=True)]
            self._lag = (1 - a) * (self._lag + Te)  # the average's delay on a ramp [s]
        if not all(pw > self._min_snr * sg for pw, sg in zip(self._powers, sigma,
                                                               strict=True)):
            return
        _, gain, v = self.shape_inverse(self._powers)
        if not (math.isfinite(gain) and gain > 0 and math.isfinite(v)):
            return
        r = v * sum(sg * sg for sg in sigma) / len(sigma)  # variance of log(gain), 1 sample
        fading = self.channel.fade_variance
        if fading:  # ... and the fading the average kept
            r += fading * a / (2 - a)
        if r > self.max_variance:  # far off the peak: the pair barely fixes the gain
            return
        # The averaged powers lag a trend: they measure the log-gain of ``lag`` s ago.
        lag = self._lag
        h0, h1 = p00 - lag * p01, p01 - lag * p11  # H P, H = [1, -lag]
        den = h0 - lag * h1 + r
        k0, k1 = h0 / den, h1 / den
        innovation = math.log(gain / self.model_gain) - (s0 - lag * s1)
        self._s = (s0 + k0 * innovation, s1 + k1 * innovation)
        self._P = (p00 - k0 * h0, p01 - k0 * h1, p11 - k1 * h1)
        # A significant trend (a drift, not a wobble) is followed closely.
        moving = abs(self._s[1]) > 3 * math.sqrt(self._P[2])
        est, band = self.estimate, self.deadband_moving if moving else self.deadband
        self.ratio = min(max(self.ratio, est / (1 + band)), est / (1 - band))

    def _compiled_update(self, y, noise_std) -> None:
        """:meth:`update` in one compiled call, on this object's own state."""
        sigma = ([v * self.ratio for v in self._nominal_sigma] if noise_std is None
                 else np.asarray(noise_std, dtype=float).tolist())
        kept = self._powers is not None
        state = np.array([*self._s, *self._P, kept, 0.0 if not kept else self._lag,
                          self.ratio])
        powers = np.array(self._powers if kept else [0.0] * len(sigma))
        if compiled_gain.gain_update(np.asarray(y, dtype=float), np.asarray(sigma), state,
                                     powers, self.Te, *self._Q, self.alpha_powers,
                                     self._min_snr, self.model_gain,
                                     self.channel.fade_variance, self.max_variance,
                                     self.deadband, self.deadband_moving, *self.shape):
            self._sigma = sigma
        s0, s1, p00, p01, p11, kept, lag, ratio = state.tolist()
        self._s, self._P, self.ratio = (s0, s1), (p00, p01, p11), ratio
        if kept:
            self._powers, self._lag = powers.tolist(), lag

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
