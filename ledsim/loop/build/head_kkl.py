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
from ledsim.files.resources import checkpoint_dir
from ledsim.physics.axis_model import AxisRatioModel
from ledsim.physics.head_model import HeadModel
from observer.kkl import checkpoint as ckpt
from observer.kkl.decoupled import PerAxis

#: The head's axes, in the state's order.
AXES = ("azimuth", "elevation")


#: The lenses whose pair ships (half-power field [deg]; None: the bare detector).
SHIPPED_LENSES = (None, 10.0)


def shipped_axis(name: str, lens_field_deg: float | None = None) -> Path:
    """The shipped KKL of axis ``name`` (one of :data:`AXES`), for the bare detector or
    a lens of half-power field ``lens_field_deg`` [deg]."""
    lens = "" if lens_field_deg is None else f"_lens{lens_field_deg:g}"
    return checkpoint_dir() / f"kkl_pan_tilt{lens}_{name}.safetensors"


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


def head_kkl(model: HeadModel, lens_field_deg: float | None = None) -> PerAxis:
    """The shipped KKL of a pan-tilt run whose head's model is ``model`` (behind a lens
    of half-power field ``lens_field_deg`` [deg]): each axis's observer, checked against
    that axis's system, on its ratios of the run's powers."""
    axes = [AxisRatioModel(model, a) for a in range(len(AXES))]
    observers = []
    for system, name in zip(axes, AXES, strict=True):
        path = shipped_axis(name, lens_field_deg)
        if not path.is_file():
            lens = "" if lens_field_deg is None else f" --lens-field-deg {lens_field_deg:g}"
            raise LedsimError(f"no shipped KKL for the pan-tilt's {name}{lens}: train it "
                              f"with `python scripts/train_pan_tilt.py{lens}`")
        observers.append(ckpt.load(path, system, name=f"kkl-{name}"))
    return PerAxis(model, observers, lambda y: [m.split(y) for m in axes], "kkl")
