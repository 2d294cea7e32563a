"""The base of every disturbance (:mod:`ledsim.physics.disturbances` lists them)."""

from __future__ import annotations

from ..errors import LedsimError
from .world import LinkWorld


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
