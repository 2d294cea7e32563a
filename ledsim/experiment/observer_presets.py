"""Named observer configurations: the paper's literal one and the shipped default.

Measured against each other by ``scripts/ablation.py`` (numbers in ``docs/observer.md``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from observer.kkl.fixed_gain import KKLDesign

if TYPE_CHECKING:  # torch is imported only when training
    from observer.kkl.training import TrainingConfig

from ledsim.errors import LedsimError

#: Names accepted by :func:`observer_preset` (``ledsim train --design``).
PRESETS = ("default", "low-light", "slow", "deep", "paper", "scheduled")

#: Filter rates r of the default design: eigenvalues 1 - Te r per photodiode. The
#: paper's slowest rate (r = 1, eigenvalue 0.99) makes T too hard to learn precisely.
DEFAULT_RATES = (2.0, 4.0, 6.0, 8.0, 10.0)
#: Low light (optional): longer memory (slowest eigenvalue 0.997) and wider maps.
LOW_LIGHT_RATES = (0.3, 0.6, 1.2, 2.5, 5.0, 10.0)
#: The slow half of the ``kkl-handover`` estimator (slowest eigenvalue 0.999): it never
#: has to forget an initial guess, since the fast default observer seeds it.
SLOW_RATES = (0.1, 0.2, 0.5, 1.0, 2.5, 5.0, 10.0)


def observer_preset(name: str, Te: float) -> tuple[KKLDesign, TrainingConfig]:
    """``"paper"``: A, B and training as written in the paper (Adam on L_dyn, then on
    L_recon, noise-free z). ``"default"``: y1 and y2 filtered separately, exact
    least-squares output layers, and a decoder trained on the z noise it will see.
    ``"low-light"``: the default with slower filters and 1000-unit maps: lower RMSE on
    weak links, but slower to forget its initial guess (``docs/observer.md``).
    ``"slow"``: slower still (rates 0.1-10), the long-memory half of ``kkl-handover``.
    ``"deep"``: the best gradient-trained observer of ``scripts/ablation.py``
    (``docs/ablation.md``): a decoder of two hidden layers, Adam on every weight of T
    and T* started from the least-squares solution. About 2x the default's error.
    ``"scheduled"`` (the gain-scheduled KKL) is trained by :func:`train_preset`."""
    from observer.kkl.training import TrainingConfig

    if name == "paper":
        return KKLDesign.paper(Te), TrainingConfig(
            output_solve=False, encoder_epochs=30, decoder_epochs=30, decoder_noise="none")
    if name == "default":
        return KKLDesign.split(Te, DEFAULT_RATES, name="default"), TrainingConfig(
            decoder_hidden=750, decoder_feature_scale=2.0)
    if name == "low-light":
        return KKLDesign.split(Te, LOW_LIGHT_RATES, name="low-light"), TrainingConfig(
            hidden=1000, decoder_hidden=1000, decoder_feature_scale=2.0)
    if name == "deep":
        # The best gradient-trained row of docs/ablation.md: the least-squares solution
        # of maps with a 2 x 256 decoder, then 20 Adam epochs on every weight.
        return KKLDesign.split(Te, DEFAULT_RATES, name="deep"), TrainingConfig(
            decoder_layers=2, decoder_hidden=256, finetune_epochs=20, lr=1e-4,
            lr_final=1e-6)
    if name == "slow":
        return KKLDesign.split(Te, SLOW_RATES, name="slow"), TrainingConfig(
            hidden=1000, decoder_hidden=1000, decoder_feature_scale=2.0)
    if name == "scheduled":
        raise LedsimError("the 'scheduled' design is trained by train_preset (its maps "
                          "are tables over the gain, not one KKLDesign)")
    raise LedsimError(f"unknown observer preset {name!r}: choose one of {', '.join(PRESETS)}")


def train_preset(system, name: str, samples: int, seed: int, data=None,
                 progress: bool = False):
    """Train the observer of preset ``name`` on ``system`` (``samples`` uniform
    transitions from ``seed``, or ``data`` = (x, f(x), h(x)) given); returns the observer
    and a :class:`~observer.kkl.training.TrainingReport`.

    ``"scheduled"`` is the gain-scheduled KKL (:mod:`observer.kkl.scheduled`): its maps are
    learned over a range of gains, and it tunes its own gain while it runs
    (``docs/observer.md``). Its report's ``loss_dyn`` is the squared dynamics residual
    over z's spread at the worst grid gain, ``loss_recon`` the squared reconstruction
    error over the domain half-widths (nominal noise, mean over the grid)."""
    import numpy as np

    from observer.kkl.training import TrainingReport, generate_transitions, train_kkl

    if name != "scheduled":
        design, cfg = observer_preset(name, system.Te)
        cfg.n_samples, cfg.seed = samples, seed
        return train_kkl(system, design, cfg, data=data, progress=progress)
    from observer.kkl.scheduled import ScheduledDesign
    from observer.kkl.scheduled_training import ScheduledTrainingConfig, train_scheduled_kkl

    cfg = ScheduledTrainingConfig(seed=seed)
    if data is None:
        data = generate_transitions(system, samples, cfg.u_bar, np.random.default_rng(seed))
    obs, rep = train_scheduled_kkl(system, ScheduledDesign(), data, cfg, progress=progress)
    err = np.asarray(rep["recon_rmse"])[:, 0] / system.domain_halfwidth
    return obs, TrainingReport(loss_dyn=rep["residual_rel_worst"] ** 2,
                               loss_recon=float((err**2).sum(axis=1).mean()),
                               seconds=rep["seconds"])
