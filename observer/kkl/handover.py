"""A fast KKL observer that hands over to a slow one: converge fast, then average long.

A KKL observer's filter bank remembers its measurements for about its slowest time
constant. Slow filters average the noise of a weak link over longer, but they also take
that long to forget the initial guess, and from a bad guess they may not converge within
a run at all. :class:`HandoverKKL` runs both banks on the same measurements and starts
with the fast one; after ``handover_steps`` it sets the slow bank's state to
``z_slow = T_slow(x_hat_fast)`` (what the slow bank would hold had it always tracked
that state) and reports the slow observer's estimate from then on.
"""

from __future__ import annotations

import numpy as np

from observer.estimator import Estimator
from observer.exceptions import ObserverError
from observer.kkl.fixed_gain import KKLObserver


class HandoverKKL(Estimator):
    """``fast`` until step ``handover_steps``, then ``slow`` seeded from ``fast``.

    Args:
        fast: the KKL observer that converges from the initial guess.
        slow: the KKL observer with the longer memory (same system).
        handover_steps: steps after a reset at which the slow observer takes over
            (the fast bank's slowest time constant a few times over).
    """

    name = "kkl-handover"

    def __init__(self, fast: KKLObserver, slow: KKLObserver, handover_steps: int):
        if handover_steps < 1:
            raise ObserverError(f"handover_steps={handover_steps!r}: must be >= 1")
        super().__init__(fast.system)
        self.fast, self.slow = fast, slow
        self.handover_steps = int(handover_steps)
        self.k = 0

    @property
    def outside_domain(self) -> bool:
        """The flag of the half whose estimate is given (:attr:`Estimator.outside_domain`)."""
        return (self.fast if self.k <= self.handover_steps else self.slow).outside_domain

    def seed_run(self, seed: int) -> None:
        self.fast.seed_run(seed)
        self.slow.seed_run(seed)

    def reset(self, x0=None, covariance=None) -> None:
        self.fast.reset(x0, covariance)
        self.slow.reset(x0, covariance)
        self.k = 0

    def update(self, y) -> np.ndarray:
        xhat = self.fast.update(y)
        if self.k == self.handover_steps:
            self.slow.z = self.slow.encode(xhat)
        self.k += 1
        if self.k <= self.handover_steps:
            self.slow.update(y)  # keeps its input for predict(); its estimate is unused
            return xhat
        return self.slow.update(y)

    def predict(self, u) -> None:
        self.fast.predict(u)
        self.slow.predict(u)
