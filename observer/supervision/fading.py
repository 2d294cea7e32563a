"""A fading channel, learned sample by sample and divided out of the pair's common scale.

Scintillation scales both photodiodes' powers together, sample by sample: moderate
turbulence (index 0.1) moves each sample's power by a quarter, where a physical link's
sensor noise is 1e-4 of it, and faster than any filter of the link's gain can follow.
Both powers fade together (their correlation is 0.99 on one head), so the pair's shape,
which carries phi, keeps most of its information, and the common scale carries mostly
the fade.

:class:`FadingChannel` inverts each sample on its own for its gain and its phi
(the shape inversion), and learns from one step to the next:

- the variance of the sample's log-gain beyond what the noise explains: the common
  fading (``fade_variance``);
- the variance of its phi beyond the noise and beyond what the gimbal's encoder says
  the receiver turned: what the fading does to the shape (``shape_variance``), the noise
  the estimators must now be told.

Once the common fading outweighs the noise along the common scale, each sample's fade is
divided out of it, by the fading's share of that scale's variance (``fade``). Without a
fading learned nothing is rescaled, to the last bit.
"""

from __future__ import annotations

import math

import numpy as np

from observer import jit

compiled_gain = jit.lazy("observer.supervision.compiled_gain")


class FadingChannel:
    """What a fading channel does to the pair of powers, learned online.

    Args:
        Te: the control period [s].
        shape_inverse: ``shape_inverse(y) -> (phi, gain, v)`` for one pair of powers
            [W]: phi [rad], the gain in the units of ``model_gain`` and the variance
            ``v`` of the relative gain per unit noise variance [1/W^2].
        model_gain: the gain of the model's ``h`` in those units.
        phi_variance: ``phi_variance(phi, y, noise_std) -> variance`` of the phi
            inverted from one pair ``y`` [W] with noise ``noise_std`` [W] [rad^2]
            (None: the fading of the pair's shape is not learned).
        min_snr: both powers must exceed this many noise standard deviations [-].
        time: time constant of the learned variances [s].
        max_std: samples whose log-gain standard deviation exceeds this are not used
            (the gain tracker's rule: far off the peak, or a pair an occluder shades on
            one side, whose shape lies about phi and the gain alike) [-].
        shape: the same pair as numbers, for the compiled path
            (:mod:`observer.supervision.compiled_pair`; None: the reference only).
    """

    #: Pairs of successive samples a fading is learned from before it is believed: 50
    #: make a false one (noise alone at twice its variance) a 1e-5 chance.
    MIN_LEARNED = 50

    def __init__(self, Te: float, shape_inverse, model_gain: float, phi_variance=None,
                 min_snr: float = 5.0, time: float = 1.0, max_std: float = 0.3,
                 shape: tuple | None = None):
        self.shape_inverse = shape_inverse
        self.shape = shape
        self.model_gain = float(model_gain)
        self.phi_variance = phi_variance
        self.min_snr = float(min_snr)
        self.alpha = min(1.0, Te / time)
        self.max_variance = max_std * max_std
        self._last: tuple | None = None  # (log-gain, phi, q) of the last sample
        self._learned = 0  # pairs of successive samples learned from
        # Variances of a sample's step (fading and noise) and of its noise alone: of
        # its log-gain [-] and of its phi [rad^2].
        self.step_variance = self.noise_variance = 0.0
        self.shape_step_variance = self.shape_noise_variance = 0.0
        self.fade = 1.0  # this step's sample's [-]

    @property
    def fade_variance(self) -> float:
        """The learned variance of a sample's log-gain that the noise does not explain,
        once it outweighs the noise's: the channel's fading [-] (0: none learned)."""
        if self._learned < self.MIN_LEARNED:
            return 0.0
        return _excess(self.step_variance, self.noise_variance)

    @property
    def shape_variance(self) -> float:
        """The learned variance of a sample's inverted phi that neither the noise nor
        the encoder explains, once it outweighs the noise's: a fading channel's part
        that differs between the photodiodes [rad^2] (0: none learned; needs the
        encoder in :meth:`sample` and ``phi_variance``)."""
        if self._learned < self.MIN_LEARNED:
            return 0.0
        return _excess(self.shape_step_variance, self.shape_noise_variance)

    def sample(self, y, q: float | None, sigma: list, ratio: float) -> float:
        """Take a step's raw powers ``y`` [W] at encoder angle ``q`` [rad] in the line
        of sight's frame (None: unknown), with noise ``sigma`` [W] on each, while the
        estimator sees the gain ``ratio`` times the model's: learn the fading from the
        sample's own gain and shape, and set its fade (1: no fading learned, or the
        sample cannot be inverted). Returns the fade [-]."""
        if self.shape is not None and jit.enabled():
            return self._compiled_sample(y, q, sigma, ratio)
        self.fade = 1.0
        y = [float(v) for v in y]
        if not all(math.isfinite(v) and v > self.min_snr * sg
                   for v, sg in zip(y, sigma, strict=True)):
            self._last = None
            return self.fade
        phi, gain, v = self.shape_inverse(y)
        if not (math.isfinite(gain) and gain > 0 and math.isfinite(v)):
            self._last = None
            return self.fade
        var = sum(sg * sg for sg in sigma) / len(sigma)
        log_gain, noise = math.log(gain / self.model_gain), v * var
        if noise > self.max_variance:  # far off the peak (or a shaded pair): no gain
            self._last = None
            return self.fade
        last, self._last = self._last, (log_gain, phi, q)
        if last is None:
            return self.fade
        # Successive differences: the gain's slow changes (distance, waves) cancel, and
        # the encoder removes the receiver's own turning from phi's; a white fade and
        # the noise count twice. The first samples are averaged evenly (a fading channel
        # is known within the acquisition's first second, not after several).
        self._learned += 1
        a = max(self.alpha, 1.0 / self._learned)
        # The clip's floor is the noise learned so far, not this sample's own.
        self.step_variance += a * (_clipped((log_gain - last[0]) ** 2, self.step_variance,
                                            2 * (self.noise_variance or noise))
                                   - self.step_variance)
        self.noise_variance += a * (noise - self.noise_variance)
        if q is not None and last[2] is not None and self.phi_variance is not None:
            phi_noise = self.phi_variance(phi, y, math.sqrt(var))
            if math.isfinite(phi_noise):
                moved = (phi - last[1]) + (q - last[2])  # phi = phi_home - q
                self.shape_step_variance += a * (_clipped(
                    moved * moved, self.shape_step_variance,
                    2 * (self.shape_noise_variance or phi_noise))
                    - self.shape_step_variance)
                self.shape_noise_variance += a * (phi_noise - self.shape_noise_variance)
        fading = self.fade_variance
        if fading > 0.0:  # the common scale carries mostly the fade
            share = fading / (fading + noise)
            self.fade = math.exp(share * (log_gain - math.log(ratio)))
        return self.fade


    def _compiled_sample(self, y, q: float | None, sigma: list, ratio: float) -> float:
        """:meth:`sample` in one compiled call, on this object's own state."""
        last = self._last
        state = np.array([0.0, 0.0, 0.0, 0.0, 0.0, self._learned, self.step_variance,
                          self.noise_variance, self.shape_step_variance,
                          self.shape_noise_variance])
        if last is not None:
            state[:5] = 1.0, last[0], last[1], 0.0 if last[2] is None else last[2], \
                last[2] is not None
        self.fade = compiled_gain.fading_sample(
            np.asarray(y, dtype=float), 0.0 if q is None else float(q), q is not None,
            np.asarray(sigma, dtype=float), float(ratio), self.min_snr, self.model_gain,
            self.max_variance, self.alpha, float(self.MIN_LEARNED),
            self.phi_variance is not None, *self.shape, state)
        kept, log_gain, phi, _, has_q, learned, *variances = state.tolist()
        self._last = (log_gain, phi, q if has_q else None) if kept else None
        self._learned = int(learned)
        (self.step_variance, self.noise_variance, self.shape_step_variance,
         self.shape_noise_variance) = variances
        return self.fade


def _excess(step_variance: float, noise_variance: float) -> float:
    """Half the variance of successive differences over the noise's, once it outweighs
    the noise's (0 until then)."""
    excess = 0.5 * step_variance - noise_variance
    return excess if excess > noise_variance else 0.0


def _clipped(square: float, variance: float, floor: float) -> float:
    """A squared difference, at most nine times the variance learned so far (or the
    noise's ``floor``): one jump (an occluder's edge, a kick) cannot teach a fading, a
    lasting one is learned within a second or two."""
    return min(square, 9.0 * max(variance, floor))
