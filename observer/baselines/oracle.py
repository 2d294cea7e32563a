"""The oracle: an estimator handed the true state, the best any estimator can do.

It takes the same calls as every other estimator, so the control step has no special
case for it; ``truth`` is whatever supplies the true state at the current step (in
MuJoCo, the sensor's reading of phi and phidot).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from observer.estimator import Estimator
from observer.system import DiscreteSystem


class Oracle(Estimator):
    """``update`` returns ``truth()`` and ignores the measurement.

    Args:
        system: the plant (dimensions only).
        truth: returns the true state of the current step, shape ``(n_state,)``.
    """

    name = "oracle"

    def __init__(self, system: DiscreteSystem, truth: Callable[[], np.ndarray]):
        super().__init__(system)
        self.truth = truth

    def reset(self, x0=None, covariance=None) -> None:
        pass

    def update(self, y) -> np.ndarray:
        return np.array(self.truth(), dtype=float)

    def predict(self, u) -> None:
        pass
