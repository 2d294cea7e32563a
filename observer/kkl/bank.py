"""A bank of observers designed for different noise levels, one active at a time.

A KKL observer's filter bank and decoder are tuned to the measurement noise it was
trained with: its decoder is trained on the z noise it will see, and a longer memory
pays off only when the light is weak. :class:`ObserverBank` holds members trained for
several noise levels and runs the one whose design noise is nearest (in ratio) the
noise measured in the model's units. A switch re-seeds the new member from the current
estimate, so the estimate carries on.
"""

from __future__ import annotations

import math

import numpy as np

from observer.estimator import Estimator
from observer.exceptions import ObserverError


class ObserverBank(Estimator):
    """Members for several noise levels; ``select(noise_ratio)`` picks one.

    Args:
        members: estimators sharing one model (``system``) except for its noise level.
        noise_ratios: each member's design noise over the model's nominal noise [-],
            increasing.
        hysteresis: relative margin past the midpoint (in log) before a switch [-].
        dwell: calls of :meth:`select` in a row that must ask for the same other member
            before it runs (a passing disturbance of the gain does not switch).
    """

    name = "kkl"

    def __init__(self, members: list[Estimator], noise_ratios, hysteresis: float = 0.15,
                 dwell: int = 0):
        ratios = [float(r) for r in noise_ratios]
        if not members or len(members) != len(ratios) or ratios != sorted(ratios) or \
                min(ratios) <= 0:
            raise ObserverError(f"noise_ratios={noise_ratios!r}: one positive, increasing "
                                f"value per member ({len(members)})")
        super().__init__(members[0].system)
        self.members = members
        self.noise_ratios = ratios
        self.hysteresis = hysteresis
        self.dwell = int(dwell)
        self._asked = (None, 0)  # (member asked for, calls in a row)
        self.active = 0
        #: The latest estimate (None before the first update).
        self.xhat: np.ndarray | None = None

    @property
    def current(self) -> Estimator:
        return self.members[self.active]

    @property
    def outside_domain(self) -> bool:
        """The running member's flag (:attr:`Estimator.outside_domain`)."""
        return self.current.outside_domain

    def nearest(self, noise_ratio: float) -> int:
        """Index of the member whose design noise is nearest ``noise_ratio`` (in log)."""
        logs = [math.log(r) for r in self.noise_ratios]
        x = math.log(max(noise_ratio, 1e-12))
        return min(range(len(logs)), key=lambda i: abs(logs[i] - x))

    def start_with(self, noise_ratio: float) -> None:
        """Before a run: the member for ``noise_ratio`` is active (no hysteresis)."""
        self.active = self.nearest(noise_ratio)

    def select(self, noise_ratio: float, y: np.ndarray | None = None) -> bool:
        """Switch to the member for ``noise_ratio`` once it is clearly nearer (beyond the
        hysteresis); the new member starts from the current estimate and takes ``y``.
        Returns whether it switched."""
        i = self.nearest(noise_ratio)
        if i != self.active:
            a, b = sorted((self.active, i))
            mid = 0.5 * (math.log(self.noise_ratios[a]) + math.log(self.noise_ratios[b]))
            x = math.log(max(noise_ratio, 1e-12))
            if abs(x - mid) < self.hysteresis * abs(math.log(self.noise_ratios[b] /
                                                             self.noise_ratios[a])):
                i = self.active
        if i == self.active:
            self._asked = (None, 0)
            return False
        n = self._asked[1] + 1 if self._asked[0] == i else 1
        self._asked = (i, n)
        if n <= self.dwell:
            return False
        self._asked = (None, 0)
        xhat = self.xhat
        self.active = i
        if xhat is not None:
            self.current.reset(xhat)
            if y is not None:
                self.xhat = self.current.update(y)
        return True

    # -- Estimator interface ---------------------------------------------------------

    def adapt_noise(self, noise_ratio: float, y=None):
        """Before the run (``y`` None) :meth:`start_with`, then :meth:`select`; the new
        estimate when it switched."""
        if y is None:
            self.start_with(noise_ratio)
            return None
        return self.xhat if self.select(noise_ratio, y) else None

    def seed_run(self, seed: int) -> None:
        for m in self.members:
            m.seed_run(seed)

    def reset(self, x0=None, covariance=None) -> None:
        """Every member from ``x0``; the active one stays."""
        for m in self.members:
            m.reset(x0, covariance)
        self.xhat = None

    def update(self, y) -> np.ndarray:
        self.xhat = self.current.update(y)
        return self.xhat

    def predict(self, u) -> None:
        self.current.predict(u)
