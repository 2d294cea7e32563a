"""Named observer configurations: the paper's literal one and the shipped default.

Measured against each other by ``scripts/ablation.py`` (numbers in ``docs/observer.md``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from observer.kkl import KKLDesign

if TYPE_CHECKING:  # torch is imported only when training
    from observer.training import TrainingConfig

from .errors import LedsimError

#: Names accepted by :func:`observer_preset` (``ledsim train --design``).
PRESETS = ("default", "low-light", "slow", "deep", "paper")

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
    and T* started from the least-squares solution. About 2x the default's error."""
    from observer.training import TrainingConfig

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
    raise LedsimError(f"unknown observer preset {name!r}: choose one of {', '.join(PRESETS)}")
