"""The pan-tilt head's shipped KKL: one one-axis KKL per axis, each on its pair of
pointing photodiodes over the data detector (:class:`~ledsim.physics.axis_model.
AxisRatioModel`), run side by side (:class:`~observer.kkl.decoupled.PerAxis`).

The ratios hold for every distance and gain, so one pair of observers serves every
physical preset (they share one receiver); ``scripts/train_pan_tilt.py`` trains them in
:func:`reference_world` and ``docs/kkl_two_axes.md`` measured the decoupled design
against a coupled four-state KKL and the EKF.
"""

from __future__ import annotations

import functools
from pathlib import Path

from ledsim.errors import LedsimError
from ledsim.files.resources import pair_paths, shipped_axis  # noqa: F401 (here before)
from ledsim.physics.axis_model import AxisRatioModel
from ledsim.physics.head_model import HeadModel
from observer.kkl import checkpoint as ckpt
from observer.kkl.decoupled import PerAxis

#: The head's axes, in the state's order.
AXES = ("azimuth", "elevation")


#: The lenses whose pair ships (half-power field [deg]; None: the bare detector).
SHIPPED_LENSES = (None, 10.0)


def reference_world(lens_field_deg: float | None = None):
    """The world a shipped pair was trained in: ``luma`` at its 30 m, a level LED, the
    pan-tilt head with its quad (and the lens)."""
    from ledsim.loop.world_part import WorldPart

    return WorldPart(link="luma", gimbal="pan-tilt",
                     lens_field_deg=lens_field_deg).world_config()


@functools.cache
def reference_axes(lens_field_deg: float | None = None
                   ) -> tuple[AxisRatioModel, AxisRatioModel]:
    """Each axis's system in :func:`reference_world` (its head's model fitted there)."""
    from ledsim.physics.head_system import HeadSystem

    head = HeadSystem(reference_world(lens_field_deg)).model()
    return tuple(AxisRatioModel(head, a) for a in range(len(AXES)))


def train_pair(lens_field_deg: float | None = None, samples: int = 200_000,
               hidden: int = 500, seed: int = 0, progress: bool = True) -> list:
    """Each axis's KKL of the default design, trained by Algorithm 1 on its system in
    :func:`reference_world`: ``[(axis, observer, report), ...]``."""
    from dataclasses import replace

    from ledsim.experiment.observer_presets import observer_preset
    from observer.kkl.training import train_kkl

    out = []
    for name, system in zip(AXES, reference_axes(lens_field_deg), strict=True):
        design, config = observer_preset("default", system.Te)
        config = replace(config, n_samples=samples, hidden=hidden, seed=seed)
        kkl, report = train_kkl(system, design, config, progress=progress)
        out.append((name, kkl, report))
    return out


def head_kkl(model: HeadModel, lens_field_deg: float | None = None,
             checkpoint: str | Path | None = None) -> PerAxis:
    """The KKL of a pan-tilt run whose head's model is ``model`` (behind a lens of
    half-power field ``lens_field_deg`` [deg]): the shipped pair, or the user's
    ``checkpoint`` pair (:func:`pair_paths`); each axis's observer, checked against that
    axis's system, on its ratios of the run's powers."""
    axes = [AxisRatioModel(model, a) for a in range(len(AXES))]
    observers = []
    for system, name in zip(axes, AXES, strict=True):
        path = shipped_axis(name, lens_field_deg) if checkpoint is None else \
            pair_paths(checkpoint)[name]
        if not path.is_file():
            lens = "" if lens_field_deg is None else f" --lens-field-deg {lens_field_deg:g}"
            if checkpoint is not None:
                raise LedsimError(f"--checkpoint {str(checkpoint)!r}: no {str(path)!r} for "
                                  f"the pan-tilt's {name} (ledsim train --gimbal pan-tilt "
                                  "writes the pair)")
            raise LedsimError(f"no shipped KKL for the pan-tilt's {name}{lens}: train it "
                              f"with `python scripts/train_pan_tilt.py{lens}`")
        observers.append(ckpt.load(path, system, name=f"kkl-{name}"))
    return PerAxis(model, observers, lambda y: [m.split(y) for m in axes], "kkl")
