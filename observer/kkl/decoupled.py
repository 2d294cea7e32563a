"""One estimator per axis: a state of several axes estimated as independent two-state
problems, each from the outputs that see its axis alone.

A head whose outputs split by axis (a quad: each pointing pair over the boresight's
detector sees one angle, whatever the other angle and the gain) can be estimated by one
small observer per axis instead of one large one over every axis: the paper's
one-axis KKL, trained on a two-dimensional box, where a KKL over four states must learn
its maps over a four-dimensional one. :class:`PerAxis` runs them side by side and gives
the estimate in the several-axis state's order (the angles, then the rates).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from observer.estimator import Estimator
from observer.system import DiscreteSystem


class PerAxis(Estimator):
    """Estimators of two-state axes (angle, rate) run side by side.

    Args:
        system: the several-axis system (its dimensions and box; the estimate is its
            state: the angles, then the rates).
        axes: one estimator per axis, each of a system with state (angle, rate) and one
            input.
        split: ``split(y) -> [y_axis, ...]``: each axis's outputs from the system's.
        name: a label.
    """

    def __init__(self, system: DiscreteSystem, axes: Sequence[Estimator],
                 split: Callable[[np.ndarray], Sequence[np.ndarray]], name: str = "per-axis"):
        super().__init__(system)
        self.axes = list(axes)
        if 2 * len(self.axes) != system.n_state:
            raise ValueError(f"{len(self.axes)} axes for a state of {system.n_state}: give "
                             "one estimator per axis (an angle and a rate each)")
        self.split = split
        self.name = name
        self.x = system.domain_center.astype(float).copy()

    @property
    def outside_domain(self) -> bool:
        return any(e.outside_domain for e in self.axes)

    def reset(self, x0=None, covariance=None) -> None:
        x0 = self.initial_guess(x0)
        n = len(self.axes)
        for a, e in enumerate(self.axes):
            e.reset(np.array([x0[a], x0[n + a]]))
        self.x = x0

    def update(self, y) -> np.ndarray:
        parts = [e.update(part) for e, part in zip(self.axes, self.split(np.asarray(y)),
                                                   strict=True)]
        self.x = np.array([p[0] for p in parts] + [p[1] for p in parts])
        return self.x.copy()

    def predict(self, u) -> None:
        u, n = np.asarray(u, dtype=float), len(self.axes)
        # broadcast_to only where needed: it alone cost 10 us a step
        for e, v in zip(self.axes, (u if u.shape == (n,) else np.broadcast_to(u, (n,))
                                    ).tolist(), strict=True):
            e.predict(v)
