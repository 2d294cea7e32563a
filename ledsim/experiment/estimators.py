"""The one estimator factory, for the closed-form model and the MuJoCo world alike.

==========  ====================================================================
name        estimator
==========  ====================================================================
kkl         the learned KKL observer from a checkpoint (validated against the system)
kkl-paper   the same class, trained with the paper's literal recipe (closed form)
kkl-handover  the default KKL handing over to a slow-filter KKL after 3 s (closed form)
kkl-scheduled  the gain-scheduled KKL: maps learned over a range of gains, the gain
            tuned while it runs (:mod:`observer.kkl.scheduled`; MuJoCo loop, where it is
            also what ``kkl`` runs under supervision)
kkl-bank    the bank of fixed-gain KKL observers for 1x-13x noise (MuJoCo loop; the
            supervised ``kkl`` before the scheduled one)
ekf         extended Kalman filter
ukf         unscented Kalman filter
pf          bootstrap particle filter
oracle      handed the true state (MuJoCo loop only): the best any estimator can do
es          extremum seeking: a model-free hill climb on the data detector's power, which
            scans a circle (pan-tilt head only; :mod:`observer.baselines.scanning`)
scan-ekf    Solanki et al.'s scanning EKF on the data detector alone (pan-tilt head only)
==========  ====================================================================
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ledsim.errors import LedsimError
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
from observer.estimator import Estimator
from observer.kkl import checkpoint as ckpt
from observer.kkl.handover import HandoverKKL
from observer.system import DiscreteSystem


@dataclass(frozen=True)
class EstimatorEntry:
    """One estimator of the registry: what it is, its family, the worlds it runs in and
    how it is built.

    Attributes:
        name: the ``--estimator`` value.
        description: one line for ``--help``.
        family: ``kkl`` (a learned KKL observer from a checkpoint), ``bayes`` (a filter
            on the model: EKF, UKF, particle filter), ``oracle`` (handed the truth) or
            ``scanning`` (the field's one-photodiode baselines, which scan to see a
            direction: on a head with a data detector).
        build: ``build(name, system, model, settings)`` gives the estimator (None: the
            oracle, which the loop hands the truth); ``settings`` are
            :func:`build_estimator`'s keyword arguments.
        closed_form: runs on the paper's closed-form model (``ledsim evaluate``).
        loop: runs in the MuJoCo loop (``ledsim run``).
        compared: one of the loop's estimators that tables and ``ledsim demo`` compare
            (``kkl-scheduled`` is what ``kkl`` runs under supervision, so not twice).
    """

    name: str
    description: str
    family: str
    build: Callable[..., Estimator | None]
    closed_form: bool = True
    loop: bool = True
    compared: bool = True


#: When ``kkl-handover`` hands over [s]: the default bank's slowest time constant (0.5 s)
#: six times over.
HANDOVER_S = 3.0


def _kkl(name, system, model, s) -> Estimator:
    if s["checkpoint"] is None:
        raise LedsimError(f"estimator {name!r} needs a checkpoint")
    return ckpt.load(s["checkpoint"], system, model=model, use_omega=s["use_omega"],
                     name=name)


def _handover(name, system, model, s) -> Estimator:
    if s["checkpoint"] is None or s["slow_checkpoint"] is None:
        raise LedsimError("estimator 'kkl-handover' needs a fast and a slow checkpoint")
    fast, slow = (_kkl("kkl", system, model, {**s, "checkpoint": c})
                  for c in (s["checkpoint"], s["slow_checkpoint"]))
    return HandoverKKL(fast, slow, handover_steps=int(round(HANDOVER_S / system.Te)))


def _scanning(name, system, model, s) -> Estimator:
    from observer.baselines.scanning import ExtremumSeeking, ScanningEKF

    layout = getattr(getattr(model, "constants", None), "layout", None)
    if layout is None or model.n_state != 4:
        raise LedsimError(f"estimator {name!r} runs on the pan-tilt head only (it scans "
                          "its data detector on both axes): use --gimbal pan-tilt")
    cls = ExtremumSeeking if name == "es" else ScanningEKF
    return cls(model, layout.reference)


def _pf(name, system, model, s) -> Estimator:
    return ParticleFilter(model, s["particles"],
                          **({} if s["redraw"] else {"lost_chi2": math.inf}))


#: Every estimator, in the order ``--help`` lists them.
REGISTRY = (
    EstimatorEntry("kkl", "learned KKL observer (shipped checkpoint or --checkpoint)", "kkl",
                   _kkl),
    EstimatorEntry("kkl-paper", "KKL trained with the paper's literal recipe", "kkl", _kkl,
                   loop=False, compared=False),
    EstimatorEntry("kkl-handover", "default KKL handing over to a slow-filter KKL after 3 s",
                   "kkl", _handover, loop=False, compared=False),
    EstimatorEntry("kkl-scheduled", "gain-scheduled KKL that tunes its own gain (MuJoCo "
                   "loop)", "kkl", _kkl, compared=False),
    EstimatorEntry("kkl-bank", "bank of fixed-gain KKL observers for 1x-13x noise (MuJoCo "
                   "loop)", "kkl", _kkl, closed_form=False),
    EstimatorEntry("ekf", "extended Kalman filter", "bayes",
                   lambda name, system, model, s: ExtendedKalmanFilter(model)),
    EstimatorEntry("ukf", "unscented Kalman filter", "bayes",
                   lambda name, system, model, s: UnscentedKalmanFilter(model)),
    EstimatorEntry("pf", "bootstrap particle filter", "bayes", _pf),
    EstimatorEntry("oracle", "handed the true state (MuJoCo loop only)", "oracle",
                   lambda name, system, model, s: None, closed_form=False),
    EstimatorEntry("es", "extremum seeking on the data detector (pan-tilt head)",
                   "scanning", _scanning, closed_form=False, compared=False),
    EstimatorEntry("scan-ekf", "Solanki et al.'s scanning one-photodiode EKF (pan-tilt "
                   "head)", "scanning", _scanning, closed_form=False, compared=False),
)
#: name -> description, every estimator (the registry's names; kept for ``--help``).
ESTIMATORS = {e.name: e.description for e in REGISTRY}
#: What ``ledsim evaluate --estimator`` may run (the oracle has nothing to estimate there).
CLOSED_FORM_ESTIMATORS = tuple(e.name for e in REGISTRY if e.closed_form)
#: Estimators of the MuJoCo loop.
LOOP_ESTIMATORS = tuple(e.name for e in REGISTRY if e.loop)
#: The loop's estimators each once, as tables and ``ledsim demo`` compare them.
COMPARED_ESTIMATORS = tuple(e.name for e in REGISTRY if e.loop and e.compared)
#: The loop's KKL estimators (on a physical link only under supervision).
LOOP_KKL_ESTIMATORS = tuple(e.name for e in REGISTRY if e.loop and e.family == "kkl")


def entry(name: str) -> EstimatorEntry:
    """The registry's entry called ``name``; :class:`LedsimError` naming the choices."""
    for e in REGISTRY:
        if e.name == name:
            return e
    raise LedsimError(f"unknown estimator {name!r}: choose one of {', '.join(ESTIMATORS)}")


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
    settings = {"checkpoint": checkpoint, "particles": particles, "use_omega": use_omega,
                "redraw": redraw, "slow_checkpoint": slow_checkpoint}
    return entry(name).build(name, system, model, settings)
