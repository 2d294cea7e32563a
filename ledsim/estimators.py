"""The one estimator factory, for the closed-form model and the MuJoCo world alike.

==========  ====================================================================
name        estimator
==========  ====================================================================
kkl         the learned KKL observer from a checkpoint (validated against the system)
kkl-paper   the same class, trained with the paper's literal recipe (closed form)
ekf         extended Kalman filter
ukf         unscented Kalman filter
pf          bootstrap particle filter
oracle      handed the true state (MuJoCo loop only): the best any estimator can do
==========  ====================================================================
"""

from __future__ import annotations

from pathlib import Path

from observer import checkpoint as ckpt
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
from observer.estimator import Estimator
from observer.system import DiscreteSystem

from .errors import LedsimError

ESTIMATORS = {
    "kkl": "learned KKL observer (shipped checkpoint or --checkpoint)",
    "kkl-paper": "KKL trained with the paper's literal recipe",
    "ekf": "extended Kalman filter",
    "ukf": "unscented Kalman filter",
    "pf": "bootstrap particle filter",
    "oracle": "handed the true state (MuJoCo loop only)",
}


def build_estimator(name: str, system: DiscreteSystem, *, model: DiscreteSystem | None = None,
                    checkpoint: str | Path | None = None, particles: int = 2000,
                    omega: bool = True) -> Estimator | None:
    """The estimator called ``name``; None for the oracle.

    Args:
        name: a key of :data:`ESTIMATORS`.
        system: the plant; a KKL checkpoint is validated against its metadata.
        model: what the estimator computes with (f and h of the filters, f of the KKL's
            Omega correction); default ``system``. In MuJoCo this is the identified
            one-step model, since the filters need f thousands of times per step.
        checkpoint: KKL checkpoint file (required for ``kkl`` and ``kkl-paper``).
        particles: particle-filter size (its random numbers follow the run's seed:
            ``Estimator.seed_run``).
        omega: apply the KKL's Omega correction.
    """
    model = system if model is None else model
    if name in ("kkl", "kkl-paper"):
        if checkpoint is None:
            raise LedsimError(f"estimator {name!r} needs a checkpoint")
        obs = ckpt.load(checkpoint, system)
        obs.name = name
        obs.system = model
        obs.omega = omega
        return obs
    if name == "ekf":
        return ExtendedKalmanFilter(model)
    if name == "ukf":
        return UnscentedKalmanFilter(model)
    if name == "pf":
        return ParticleFilter(model, particles)
    if name == "oracle":
        return None
    raise LedsimError(f"unknown estimator {name!r}: choose one of {', '.join(ESTIMATORS)}")
