"""Where the beam is, from the pair of powers carried on the encoder (the first piece
of the minimum-time acquisition, :mod:`ledsim.agent.slew`)."""

from __future__ import annotations

import math
from collections import deque

from ledsim.constants import LinkConstants
from ledsim.radiometry.optics import pair_phi_variance, pair_shape_inverse

__all__ = ["BeamFix"]


class BeamFix:
    """Where the beam is, in the encoder's frame, from the pair of powers.

    Args:
        constants: the link (the receiver response, dphi, Te).
        phi_ref: the alignment target, phi at the intensity maximum [rad].
        detect_sigmas: a sample counts when both powers are this many noise standard
            deviations above zero [-].
        max_phi: samples whose inverted |phi| exceeds this are left out [rad] (far in the
            tail the log-ratio is dominated by the shoulder's model error).
        memory: samples older than this are forgotten [s]: they may no longer hold (a
            drifting transmitter, a hull turning without the IMU).
        agree_sigmas: a sample further than this many standard deviations from the
            others' fix starts the fix afresh (the beam moved, or the older samples were
            a partly shaded pair, whose shape lies about phi) [-].
    """

    def __init__(self, constants: LinkConstants, phi_ref: float, detect_sigmas: float = 4.0,
                 max_phi: float = 0.8, memory: float = 0.3, agree_sigmas: float = 4.0):
        self.c = constants
        self.phi_ref = phi_ref
        self.detect_sigmas = detect_sigmas
        self.max_phi = max_phi
        self.memory_steps = max(1, int(round(memory / constants.Te)))
        self.agree_sigmas = agree_sigmas
        # (step, weight [1/rad^2], target encoder angle [rad], gain [W]) of each sample.
        self._samples: deque = deque()
        self._step = 0
        # While the samples stand: their weighted means by column, and (at -1) their weight.
        self._means: dict[int, float | None] = {}

    def clear(self) -> None:
        self._samples.clear()
        self._means.clear()

    @property
    def samples(self) -> int:
        return len(self._samples)

    def add(self, y, q: float, noise_std: float, extra_variance: float = 0.0) -> bool:
        """Take the powers ``y`` [W] measured at encoder angle ``q`` [rad] with noise
        ``noise_std`` [W] (one call a control step, usable or not), whose inverted phi
        also carries ``extra_variance`` [rad^2] that the noise does not explain (a
        fading channel's, on the pair's shape); True when the sample was usable."""
        self._step += 1
        while self._samples and self._step - self._samples[0][0] > self.memory_steps:
            self._samples.popleft()
            self._means.clear()
        powers = [float(v) for v in y]
        bar = self.detect_sigmas * noise_std
        if not all(p > bar for p in powers):  # dark, gated out (NaN) or in the noise
            return False
        phi, gain, _ = pair_shape_inverse(powers, self.c)
        if not abs(phi) <= self.max_phi:
            return False
        var = self.phi_variance(phi, powers, noise_std) + extra_variance
        if not var > 0 or not math.isfinite(var):
            return False
        target = q + phi - self.phi_ref
        if self._samples and abs(target - self.target) > self.agree_sigmas * math.sqrt(
                var + self.stderr**2):
            self._samples.clear()
        self._samples.append((self._step, 1.0 / var, target, gain))
        self._means.clear()
        return True

    def phi_variance(self, phi: float, powers, noise_std: float) -> float:
        """Variance of one sample's inverted phi [rad^2]: the log-ratio's noise
        sigma^2 (1/P1^2 + 1/P2^2) over its squared slope in phi there (``powers`` [W])."""
        return pair_phi_variance(phi, powers, noise_std, self.c)

    def _weighted_mean(self, column: int) -> float | None:
        """The inverse-variance weighted mean of a sample column (None: no sample), kept
        until the samples change (a step asks for the target several times)."""
        if column not in self._means:
            w = self._weight()
            self._means[column] = sum(s[1] * s[column] for s in self._samples) / w \
                if w > 0 else None
        return self._means[column]

    def _weight(self) -> float:
        """The samples' summed weight [1/rad^2], kept as the means are."""
        if -1 not in self._means:
            self._means[-1] = sum(s[1] for s in self._samples)
        return self._means[-1]

    @property
    def target(self) -> float | None:
        """Encoder angle [rad] at which phi is the alignment target (None: no sample)."""
        return self._weighted_mean(2)

    @property
    def stderr(self) -> float:
        """Standard error of :attr:`target` [rad] (inf: no sample)."""
        w = self._weight()
        return 1.0 / math.sqrt(w) if w > 0 else math.inf

    @property
    def gain(self) -> float | None:
        """The transmitter gain the samples saw [W], weighted as the target (None: no
        sample)."""
        return self._weighted_mean(3)
