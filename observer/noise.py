"""The measurement noise of a run, as one object that everything reads.

The sensor draws from it, the estimators weigh by it (their R), the supervisor starts
its noise level from it, the environment bounds its observations by it and the link
budget turns it into a bit error rate. The paper's is zero-mean Gaussian, the same
standard deviation on every output, independent between outputs and steps. A physical
receiver adds terms that depend on the clean output (:meth:`MeasurementNoise.std_at`):
the signal's shot noise, a variance proportional to the signal, and the quantisation
of an ADC behind an automatic gain control (:class:`Digitiser`), whose step follows the
signal's range. Each channel has its noise bandwidth: the pointing samples once a
control period (1 / (2 Te)), the data at the bit rate (:meth:`MeasurementNoise.at_bandwidth`).
"""

from __future__ import annotations

import bisect
import functools
import math
from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class Digitiser:
    """An ADC behind a stepped receiver gain (automatic gain control).

    The gain control spans ``decades`` decades in steps of ``step_ratio`` (2: the 6 dB
    steps of a programmable-gain amplifier). It picks the most sensitive range whose
    full scale, ``full_scale x step_ratio^-j``, holds twice the clean signal; the ADC
    rounds to ``2^bits`` steps over +-that range and clips beyond it. Above the least
    sensitive range the detector's own gain turns down ``headroom_steps`` more steps (a
    photomultiplier's control voltage, an avalanche photodiode's bias), and above that
    the receiver saturates at :attr:`saturation`. The gain control follows
    the clean signal (it averages over many samples), so the step is a function of it:
    with 6 dB steps and 12 bits the step is 2.8e-4 to 5.6e-4 of the signal (rms).

    A sample is the mean of ``conversions`` conversions over the control period (an ADC
    at ``conversions / Te``). Where the analog noise of one conversion (its bandwidth
    ``conversions`` times the sample's) is at least half a step it dithers the
    quantisation, and the mean's rounding error is a noise of variance
    step^2 / (12 conversions); below that the rounding is not dithered, and the sample
    is the one conversion rounded (an error fixed by the signal, which no averaging
    removes).

    Attributes:
        bits: ADC resolution [bits].
        full_scale: the output that saturates the least sensitive range [output unit].
        decades: the span of the gain control [decades].
        step_ratio: the ratio of neighbouring ranges' full scales [-].
        conversions: conversions averaged into one sample [-].
        headroom_steps: steps of ``step_ratio`` the detector's gain turns down above
            the ADC's least sensitive range [-] (0: none; the ranges below are the same).
    """

    bits: int = 12
    full_scale: float = 1e-3
    decades: int = 6
    step_ratio: float = 2.0
    conversions: int = 1
    headroom_steps: int = 0

    def __post_init__(self) -> None:
        if not (isinstance(self.bits, int) and 1 <= self.bits <= 32):
            raise ValueError(f"bits={self.bits!r} is not allowed: must be an integer in 1..32")
        if not (self.full_scale > 0 and math.isfinite(self.full_scale)):
            raise ValueError(f"full_scale={self.full_scale!r} is not allowed: must be > 0")
        if not (isinstance(self.decades, int) and 1 <= self.decades <= 12):
            raise ValueError(f"decades={self.decades!r} is not allowed: must be an integer "
                             "in 1..12")
        if not (1.0 < self.step_ratio <= 10.0):
            raise ValueError(f"step_ratio={self.step_ratio!r} is not allowed: must be in "
                             "(1, 10]")
        if not (isinstance(self.conversions, int) and 1 <= self.conversions <= 10**7):
            raise ValueError(f"conversions={self.conversions!r} is not allowed: must be an "
                             "integer in 1..1e7")
        if not (isinstance(self.headroom_steps, int) and 0 <= self.headroom_steps <= 40):
            raise ValueError(f"headroom_steps={self.headroom_steps!r} is not allowed: must "
                             "be an integer in 0..40")

    @property
    def n_ranges(self) -> int:
        """Number of gain ranges [-]."""
        return int(math.ceil(self.decades * math.log(10.0) / math.log(self.step_ratio)
                             - 1e-9)) + 1

    @functools.cached_property
    def tops(self) -> tuple[float, ...]:
        """The ranges' full scales, most sensitive first [output unit]."""
        return tuple(self.full_scale * self.step_ratio ** -j
                     for j in range(self.n_ranges - 1, -self.headroom_steps - 1, -1))

    @property
    def saturation(self) -> float:
        """The output at which the least sensitive range clips: ``full_scale`` with
        the detector's gain turned down its ``headroom_steps`` [output unit]."""
        return self.full_scale * self.step_ratio ** self.headroom_steps

    def range_of(self, clean) -> np.ndarray:
        """Full scale of the range the gain control picks for ``clean`` [output unit]:
        the most sensitive that holds twice it (comparisons only, so a value and an
        array of it pick alike)."""
        level = 2.0 * np.abs(np.asarray(clean, dtype=float))
        tops = np.asarray(self.tops)
        return tops[np.minimum(np.searchsorted(tops, level), tops.size - 1)]

    def range_at(self, clean: float) -> float:
        """:meth:`range_of` for one value, in plain floats (the per-step path)."""
        tops = self.tops
        return tops[min(bisect.bisect_left(tops, 2.0 * abs(clean)), len(tops) - 1)]

    def step(self, clean) -> np.ndarray:
        """Quantisation step at ``clean`` [output unit]: two full scales over 2^bits."""
        return 2.0 * self.range_of(clean) / 2**self.bits

    def dithered(self, analog_std, clean) -> np.ndarray:
        """Whether one conversion's analog noise (``analog_std`` [output unit] is the
        sample's) reaches half a step at ``clean``, so that averaging resolves below
        the step."""
        return (np.asarray(analog_std, dtype=float) * math.sqrt(self.conversions)
                >= 0.5 * self.step(clean)) & (self.conversions > 1)

    def apply(self, values, clean) -> np.ndarray:
        """``values`` rounded to the step and clipped to the range picked for ``clean``."""
        top = self.range_of(clean)
        q = 2.0 * top / 2**self.bits
        return np.clip(np.round(np.asarray(values, dtype=float) / q) * q, -top, top)


@dataclass(frozen=True)
class MeasurementNoise:
    """Additive output noise v_k ~ N(0, diag(std^2)).

    Attributes:
        nominal_std: standard deviation of one output sample at noise scale 1, in the
            output's unit (W for a photodiode power).
        n_output: number of outputs it is drawn for (photodiodes) [-].
        scale: the run's noise scale: the standard deviation over the nominal [-].
        shot_coefficient: the signal's shot noise: variance per unit of clean output at
            scale 1 [output unit] (0: none, the paper's).
        digitiser: the ADC and gain control the outputs pass (None: none, the paper's).
    """

    nominal_std: float
    n_output: int = 2
    scale: float = 1.0
    shot_coefficient: float = 0.0
    digitiser: Digitiser | None = None

    def __post_init__(self) -> None:
        if not (self.nominal_std >= 0 and np.isfinite(self.nominal_std)):
            raise ValueError(f"nominal_std={self.nominal_std!r} is not allowed: must be "
                             ">= 0 and finite")
        if not (self.scale >= 0 and np.isfinite(self.scale)):
            raise ValueError(f"scale={self.scale!r} is not allowed: must be >= 0 and finite")
        if self.n_output < 1:
            raise ValueError(f"n_output={self.n_output!r} is not allowed: must be >= 1")
        if not (self.shot_coefficient >= 0 and np.isfinite(self.shot_coefficient)):
            raise ValueError(f"shot_coefficient={self.shot_coefficient!r} is not allowed: "
                             "must be >= 0 and finite")

    @property
    def std(self) -> float:
        """Standard deviation of one sample of each output without a signal: the floor
        [output unit] (the whole noise when it does not depend on the signal)."""
        return self.nominal_std * self.scale

    @property
    def signal_dependent(self) -> bool:
        """Whether the noise depends on the clean output (shot noise or an ADC)."""
        return self.shot_coefficient > 0 or self.digitiser is not None

    def analog_std(self, clean) -> np.ndarray:
        """Standard deviation before the ADC at clean outputs ``clean`` [output unit]:
        scale x sqrt(floor^2 + shot_coefficient x max(clean, 0)), clean's shape."""
        clean = np.maximum(np.asarray(clean, dtype=float), 0.0)
        return self.scale * np.sqrt(self.nominal_std**2 + self.shot_coefficient * clean)

    def std_at(self, clean=None) -> np.ndarray:
        """Standard deviation of each output given its noise-free value ``clean`` [output
        unit]: the analog noise and the ADC's quantisation (step^2 / 12), shape
        ``(n_output,)`` (``clean``'s shape when given). Without ``clean``: the floor."""
        if clean is None or not self.signal_dependent:
            return np.full(self.n_output if clean is None else np.shape(clean), self.std)
        if np.ndim(clean) == 1 and self.digitiser is not None:  # one output vector
            return np.array([self._std_one(c) for c in np.asarray(clean, float).tolist()])
        analog = self.analog_std(clean)
        if self.digitiser is None:
            return analog
        return np.sqrt(analog**2 + self._quantisation_var(analog, clean))

    def _quantisation_var(self, analog, clean) -> np.ndarray:
        dig = self.digitiser
        var = dig.step(clean) ** 2 / 12.0
        return np.where(dig.dithered(analog, clean), var / dig.conversions, var)

    def measure(self, clean, rng: np.random.Generator) -> np.ndarray:
        """A noisy reading of the clean outputs ``clean`` (one normal draw an output, as
        :meth:`sample`): :meth:`measure_with` of fresh draws."""
        clean = np.asarray(clean, dtype=float)
        return self.measure_with(rng.standard_normal(clean.shape), clean)

    def measure_with(self, draws, clean) -> np.ndarray:
        """The reading of ``clean`` from standard normal ``draws`` of its shape: analog
        noise at the signal, then the ADC: a dithered mean of conversions (its
        quantisation noise added to the draw's), or one undithered conversion rounded."""
        clean = np.asarray(clean, dtype=float)
        if clean.ndim == 1 and self.digitiser is not None:  # one reading: plain floats
            return np.array([self._measure_one(float(z), float(c))
                             for z, c in zip(np.asarray(draws).tolist(), clean.tolist(),
                                             strict=True)])
        analog = self.analog_std(clean)
        if self.digitiser is None:
            return clean + draws * analog
        dither = self.digitiser.dithered(analog, clean)
        var = np.where(dither, analog**2 + self._quantisation_var(analog, clean), analog**2)
        y = clean + draws * np.sqrt(var)
        top = self.digitiser.range_of(clean)
        return np.where(dither, np.clip(y, -top, top), self.digitiser.apply(y, clean))

    def _terms_one(self, c: float) -> tuple[float, float, float, bool]:
        """(analog std, range, step, dithered) of one clean output ``c``, in plain
        floats: the same operations as :meth:`analog_std` and :class:`Digitiser`'s."""
        dig = self.digitiser
        analog = self.scale * math.sqrt(self.nominal_std**2 + self.shot_coefficient
                                        * max(c, 0.0))
        top = dig.range_at(c)
        step = 2.0 * top / 2**dig.bits
        dither = dig.conversions > 1 and analog * math.sqrt(dig.conversions) >= 0.5 * step
        return analog, top, step, dither

    def _std_one(self, c: float) -> float:
        """:meth:`std_at` of one output in plain floats (the per-step path)."""
        analog, _, step, dither = self._terms_one(c)
        var = step**2 / 12.0
        if dither:
            var = var / self.digitiser.conversions
        return math.sqrt(analog**2 + var)

    def _measure_one(self, z: float, c: float) -> float:
        """:meth:`measure_with` of one output, the same operations in plain floats (the
        per-step path, several times faster at this size; a batch's row is equal)."""
        analog, top, step, dither = self._terms_one(c)
        if dither:
            y = c + z * math.sqrt(analog**2 + step**2 / 12.0 / self.digitiser.conversions)
            return min(max(y, -top), top)
        y = c + z * math.sqrt(analog**2)
        return min(max(round(y / step) * step, -top), top)

    def at_bandwidth(self, ratio: float) -> MeasurementNoise:
        """The noise of a channel whose bandwidth is ``ratio`` times this one's [-]: white
        terms' variances times ``ratio``, and no ADC (the data channel's slicer)."""
        return replace(self, nominal_std=self.nominal_std * math.sqrt(ratio),
                       shot_coefficient=self.shot_coefficient * ratio, digitiser=None)

    def covariance(self, clean=None) -> np.ndarray:
        """R = diag(std^2) (at the clean outputs ``clean``, when given), shape
        ``(n_output, n_output)``."""
        return np.diag(self.std_at(clean) ** 2)

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """One draw of v_k, shape ``(n_output,)``."""
        return rng.standard_normal(self.n_output) * self.std

    def scaled(self, factor: float) -> MeasurementNoise:
        """The same noise with its standard deviation times ``factor``."""
        return replace(self, scale=self.scale * factor)

    def nominal(self) -> MeasurementNoise:
        """The same noise at scale 1 (what a model trained on the nominal assumes)."""
        return replace(self, scale=1.0)
