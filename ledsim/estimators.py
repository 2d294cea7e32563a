"""The one estimator factory, for the closed-form model and the MuJoCo world alike.

==========  ====================================================================
name        estimator
==========  ====================================================================
kkl         the learned KKL observer from a checkpoint (validated against the system)
kkl-paper   the same class, trained with the paper's literal recipe (closed form)
kkl-handover  the default KKL handing over to a slow-filter KKL after 3 s (closed form)
kkl-scheduled  the gain-scheduled KKL: maps learned over a range of gains, the gain
            tuned while it runs (:mod:`observer.scheduled`; MuJoCo loop, where it is
            also what ``kkl`` runs under supervision)
kkl-bank    the bank of fixed-gain KKL observers for 1x-13x noise (MuJoCo loop; the
            supervised ``kkl`` before the scheduled one)
ekf         extended Kalman filter
ukf         unscented Kalman filter
pf          bootstrap particle filter
oracle      handed the true state (MuJoCo loop only): the best any estimator can do
==========  ====================================================================
"""

from __future__ import annotations

import math
from pathlib import Path

from observer import checkpoint as ckpt
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
from observer.estimator import Estimator
from observer.handover import HandoverKKL
from observer.system import DiscreteSystem

from .errors import LedsimError

ESTIMATORS = {
    "kkl": "learned KKL observer (shipped checkpoint or --checkpoint)",
    "kkl-paper": "KKL trained with the paper's literal recipe",
    "kkl-handover": "default KKL handing over to a slow-filter KKL after 3 s",
    "kkl-scheduled": "gain-scheduled KKL that tunes its own gain (MuJoCo loop)",
    "kkl-bank": "bank of fixed-gain KKL observers for 1x-13x noise (MuJoCo loop)",
    "ekf": "extended Kalman filter",
    "ukf": "unscented Kalman filter",
    "pf": "bootstrap particle filter",
    "oracle": "handed the true state (MuJoCo loop only)",
}


#: When ``kkl-handover`` hands over [s]: the default bank's slowest time constant (0.5 s)
#: six times over.
HANDOVER_S = 3.0


def build_estimator(name: str, system: DiscreteSystem, *, model: DiscreteSystem | None = None,
                    checkpoint: str | Path | None = None, particles: int = 2000,
                    use_omega: bool = True, redraw: bool = True,
                    slow_checkpoint: str | Path | None = None) -> Estimator | None:
    """The estimator called ``name``; None for the oracle.

    Args:
        name: a key of :data:`ESTIMATORS`.
        system: the plant; a KKL checkpoint is validated against its metadata.
        model: what the estimator computes with (f and h of the filters, f of the KKL's
            Omega correction); default ``system``. In MuJoCo this is the identified
            one-step model, since the filters need f thousands of times per step.
        checkpoint: KKL checkpoint file (required for ``kkl``, ``kkl-paper`` and
            ``kkl-scheduled``; a scheduled checkpoint gives the scheduled KKL either way).
        particles: particle-filter size (its random numbers follow the run's seed:
            ``Estimator.seed_run``).
        use_omega: apply the KKL's Omega correction.
        redraw: the particle filter re-draws part of its particles when every one of them
            is implausible (off: a supervisor handles losses).
        slow_checkpoint: the slow half of ``kkl-handover`` (``checkpoint`` is its fast
            half).
    """
    model = system if model is None else model
    if name in ("kkl", "kkl-paper", "kkl-scheduled", "kkl-bank"):
        if checkpoint is None:
            raise LedsimError(f"estimator {name!r} needs a checkpoint")
        return ckpt.load(checkpoint, system, model=model, use_omega=use_omega, name=name)
    if name == "kkl-handover":
        if checkpoint is None or slow_checkpoint is None:
            raise LedsimError("estimator 'kkl-handover' needs a fast and a slow checkpoint")
        fast, slow = (build_estimator("kkl", system, model=model, checkpoint=c,
                                      use_omega=use_omega)
                      for c in (checkpoint, slow_checkpoint))
        return HandoverKKL(fast, slow, handover_steps=int(round(HANDOVER_S / system.Te)))
    if name == "ekf":
        return ExtendedKalmanFilter(model)
    if name == "ukf":
        return UnscentedKalmanFilter(model)
    if name == "pf":
        return ParticleFilter(model, particles, **({} if redraw else {"lost_chi2": math.inf}))
    if name == "oracle":
        return None
    raise LedsimError(f"unknown estimator {name!r}: choose one of {', '.join(ESTIMATORS)}")
