"""The measurement noise of a run, as one object that everything reads.

The sensor draws from it, the estimators weigh by it (their R), the supervisor starts
its noise level from it, the environment bounds its observations by it and the link
budget turns it into a bit error rate. Today it is the paper's: zero-mean Gaussian,
the same standard deviation on every output, independent between outputs and steps.
A signal-dependent receiver (shot noise, an amplifier) gives it terms in the clean
outputs: :meth:`MeasurementNoise.std_at` is where they enter.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class MeasurementNoise:
    """Additive output noise v_k ~ N(0, diag(std^2)).

    Attributes:
        nominal_std: standard deviation of one output sample at noise scale 1, in the
            output's unit (W for a photodiode power).
        n_output: number of outputs it is drawn for (photodiodes) [-].
        scale: the run's noise scale: the standard deviation over the nominal [-].
    """

    nominal_std: float
    n_output: int = 2
    scale: float = 1.0

    def __post_init__(self) -> None:
        if not (self.nominal_std >= 0 and np.isfinite(self.nominal_std)):
            raise ValueError(f"nominal_std={self.nominal_std!r} is not allowed: must be "
                             ">= 0 and finite")
        if not (self.scale >= 0 and np.isfinite(self.scale)):
            raise ValueError(f"scale={self.scale!r} is not allowed: must be >= 0 and finite")
        if self.n_output < 1:
            raise ValueError(f"n_output={self.n_output!r} is not allowed: must be >= 1")

    @property
    def std(self) -> float:
        """Standard deviation of one sample of each output [output unit]."""
        return self.nominal_std * self.scale

    def std_at(self, clean=None) -> np.ndarray:
        """Standard deviation of each output given its noise-free value ``clean`` (not
        used yet: the paper's noise does not depend on the signal), shape
        ``(n_output,)``."""
        return np.full(self.n_output, self.std)

    def covariance(self) -> np.ndarray:
        """R = diag(std^2), shape ``(n_output, n_output)``."""
        return np.diag(self.std_at() ** 2)

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """One draw of v_k, shape ``(n_output,)``."""
        return rng.standard_normal(self.n_output) * self.std

    def scaled(self, factor: float) -> MeasurementNoise:
        """The same noise with its standard deviation times ``factor``."""
        return replace(self, scale=self.scale * factor)

    def nominal(self) -> MeasurementNoise:
        """The same noise at scale 1 (what a model trained on the nominal assumes)."""
        return replace(self, scale=1.0)
