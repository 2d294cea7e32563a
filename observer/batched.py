"""Estimators over N trajectories at once: the same filters, one (N, ...) array each.

``batched(template, n)`` returns N copies of an estimator stepped together:
``update(Y)`` takes the measurements of every trajectory, shape (N, p), and returns the
estimates, (N, n); ``predict(U)`` takes one input per trajectory, (N,). Each copy gives
the numbers the single-trajectory estimator gives (to round-off), missing samples and
divergence restarts included, because the vectorised code follows the same equations
branch by branch:

===================  ===========================================================
template             batched form
===================  ===========================================================
KKLObserver          z (N, q); one decoder pass, one stacked encoder pass for Omega
ExtendedKalmanFilter x (N, n), P (N, n, n); worlds grouped by which outputs are usable
UnscentedKalmanFilter  the same, sigma points (N, 2n+1, n)
ParticleFilter       particles (N, M, n) through one f and one h; each copy keeps its
                     own random generator, so its draws match the single filter's
anything else        :class:`PerTrajectory`: N independent copies in a loop
===================  ===========================================================
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence

import numpy as np

from .estimator import Estimator, usable_mask
from .kkl import KKLObserver


class BatchedEstimator:
    """N copies of one estimator; see the module docstring."""

    def __init__(self, template: Estimator, n: int):
        self.template = template
        self.system = template.system
        self.n = int(n)

    def reset(self, x0: np.ndarray | None = None) -> None:
        raise NotImplementedError

    def update(self, y: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def predict(self, u: np.ndarray) -> None:
        raise NotImplementedError

    def usable_groups(self, y: np.ndarray):
        """(trajectory indices, usable outputs) for each pattern of usable outputs in
        ``y`` (N, p), skipping the trajectories with none (they take no update)."""
        ok = usable_mask(self.system, y)
        patterns, inverse = np.unique(ok, axis=0, return_inverse=True)
        for j, pattern in enumerate(patterns):
            if pattern.any():
                yield np.flatnonzero(inverse.reshape(-1) == j), pattern

    def _guess(self, x0) -> np.ndarray:
        guess = self.system.domain_center if x0 is None else x0
        return np.array(np.broadcast_to(np.asarray(guess, dtype=float),
                                        (self.n, self.system.n_state)))


class PerTrajectory(BatchedEstimator):
    """Fallback: N independent estimators stepped in a loop (any :class:`Estimator`)."""

    def __init__(self, estimators: Sequence[Estimator]):
        super().__init__(estimators[0], len(estimators))
        self.members = list(estimators)

    def reset(self, x0=None) -> None:
        for k, e in enumerate(self.members):
            e.reset(None if x0 is None else np.asarray(x0)[k])

    def update(self, y) -> np.ndarray:
        return np.stack([e.update(yk) for e, yk in zip(self.members, y, strict=True)])

    def predict(self, u) -> None:
        for e, uk in zip(self.members, np.asarray(u, dtype=float).tolist(), strict=True):
            e.predict(uk)


class BatchedKKL(BatchedEstimator):
    """:class:`KKLObserver` over N trajectories (z of shape (N, q))."""

    def __init__(self, template: KKLObserver, n: int):
        super().__init__(template, n)
        self.reset()

    def reset(self, x0=None) -> None:
        self.z = self.template.encode(self._guess(x0))
        self._y = None
        self._xhat = None

    def update(self, y) -> np.ndarray:
        t = self.template
        y = np.asarray(y, dtype=float)
        self._xhat = t.decode(self.z)
        ok = usable_mask(self.system, y)
        if not ok.all():
            y = np.where(ok, y, self.system.h(self._xhat))
        self._y = y
        return self._xhat.copy()

    def predict(self, u) -> None:
        t = self.template
        u = np.asarray(u, dtype=float)
        z_next = t.eigenvalues * self.z + self._y @ t.B.T
        moved = u != t.u_bar
        if t.omega and moved.any():
            k = np.flatnonzero(moved)
            xh, f = self._xhat[k], self.system.f
            both = t.encoder_T(np.concatenate([f(xh, u[k]), f(xh, np.full(k.size, t.u_bar))]))
            z_next[k] += both[:k.size] - both[k.size:]
        self.z = z_next


def batched(template: Estimator, n: int,
            seeded: Callable[[Estimator, int], None] | None = None) -> BatchedEstimator:
    """N copies of ``template`` stepped together (see the module docstring).

    Args:
        template: the estimator of one trajectory (its configuration is copied).
        n: number of trajectories.
        seeded: ``seeded(copy, k)`` gives copy ``k`` its random numbers (the particle
            filter's ``seed_run``); estimators without randomness ignore it.
    """
    from .baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
    from .baselines.batched import BatchedEKF, BatchedParticleFilter, BatchedUKF

    kind = type(template)
    if kind is KKLObserver:
        return BatchedKKL(template, n)
    if kind is ExtendedKalmanFilter:
        return BatchedEKF(template, n)
    if kind is UnscentedKalmanFilter:
        return BatchedUKF(template, n)
    # Copies share the model (it may hold a simulator) and nothing else.
    copies = [copy.deepcopy(template, {id(template.system): template.system})
              for _ in range(n)]
    for k, c in enumerate(copies):
        if seeded is not None:
            seeded(c, k)
        c.reset()
    if kind is ParticleFilter:
        return BatchedParticleFilter(copies)
    return PerTrajectory(copies)
