"""The base of every disturbance (:mod:`ledsim.physics.disturbances` lists them)."""

from __future__ import annotations

import numpy as np

from ledsim.errors import LedsimError
from ledsim.physics.world import LinkWorld


class DisturbanceError(LedsimError):
    """Unknown disturbance name or bad parameter."""


class Disturbance:
    """Base of every disturbance: seeded at the start of a run, applied every step."""

    def reset(self, seed: int) -> None:
        """Start of a run with seed ``seed`` (disturbances with random parts reseed)."""

    def apply(self, world: LinkWorld, t: float) -> None:
        raise NotImplementedError

    #: It changes the world's model (not only its state), so worlds that run it side by
    #: side cannot share one compiled model.
    changes_model = False

    @property
    def event_end(self) -> float | None:
        """Time [s] at which a transient event (an occlusion) ends, after which the loop
        should recover; None for disturbances that last the whole run."""
        return None


class SeededDisturbance(Disturbance):
    """A disturbance with random parts: its own generator, reseeded by :meth:`reset`
    (and at construction, from its ``seed`` field), and the time since its last
    :meth:`apply` (:meth:`elapsed`). Subclasses clear their own state in
    :meth:`restart`."""

    seed: int

    def __post_init__(self):
        self.reset(self.seed)

    def reset(self, seed: int) -> None:
        self.seed = seed
        self._rng = np.random.default_rng(seed)
        self._last_t = None
        self.restart()

    def restart(self) -> None:
        """Clear the subclass's own state at the start of a run."""

    def elapsed(self, t: float) -> float | None:
        """Time since the last call [s] (None at the first), and remember ``t``."""
        dt = None if self._last_t is None else t - self._last_t
        self._last_t = t
        return dt
