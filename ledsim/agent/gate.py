"""The measurement gate in front of every estimator: occluded samples become missing.

It looks only at the measurements, so every estimator (KKL, EKF, UKF, PF) gets the same
input.
"""

from __future__ import annotations

import math

import numpy as np

from ledsim.constants import LinkConstants
from ledsim.radiometry.optics import peak_power


class DropoutGate:
    """Marks occluded samples as missing (NaN) before they reach any estimator.

    A body crossing the beam cuts the light within a few milliseconds, while turning the
    gimbal dims it smoothly. A photodiode's sample therefore counts as a dropout when it
    falls below ``floor`` W while the recent level of that photodiode (an exponential
    average of its accepted samples) was above twice the floor, and it stays one while
    the power stays below the floor. Missing samples are then handled by each
    estimator's own policy (KKL holds its prediction; Kalman and particle filters skip
    the update). After ``max_hold`` seconds the gate gives up and passes the samples
    again, so a lasting loss of light is seen as what it is.

    Args:
        constants: link constants (the floor defaults to 10% of the peak power).
        floor: power below which a sample may be a dropout [W].
        max_hold: longest dropout bridged [s] (inf: every one).
        smoothing: weight of a new sample in the recent level [-].
    """

    def __init__(self, constants: LinkConstants, floor: float | None = None,
                 max_hold: float = 1.0, smoothing: float = 0.2):
        self.floor = 0.1 * peak_power(constants) if floor is None else floor
        self.n = constants.layout.n_photodiodes
        self.max_steps = math.inf if math.isinf(max_hold) else int(round(max_hold / constants.Te))
        self.smoothing = smoothing
        self.reset()

    def reset(self) -> None:
        self._held = [0] * self.n
        self._expired = [False] * self.n  # held too long: passing the darkness on
        self._level: list | None = None

    @property
    def held(self) -> np.ndarray:
        """Steps each photodiode's current dropout has lasted [-]."""
        return np.array(self._held)

    @property
    def level(self) -> np.ndarray | None:
        """Recent level of each photodiode's accepted samples [W]."""
        return None if self._level is None else np.array(self._level)

    def __call__(self, y: np.ndarray) -> np.ndarray:
        # Plain floats: two photodiodes, and numpy's per-call cost dominated (11 us).
        y = np.asarray(y, dtype=float).tolist()
        if self._level is None:
            self._level = list(y)
        floor, a, out = self.floor, self.smoothing, []
        for i, yi in enumerate(y):
            held, level = self._held[i], self._level[i]
            low = yi < floor
            # Past max_hold a lasting darkness is passed on, every sample, until light
            # returns: the estimators and the supervisor see a blackout as one.
            self._expired[i] = low and (self._expired[i] or held >= self.max_steps)
            drop = low and (held > 0 or level > 2 * floor) and not self._expired[i]
            self._held[i] = held + 1 if drop else 0
            if not drop:
                self._level[i] = (1 - a) * level + a * yi
            out.append(math.nan if drop else yi)
        return np.array(out)

