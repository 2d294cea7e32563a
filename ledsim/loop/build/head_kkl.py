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


def shipped_axis(name: str) -> Path:
    """The shipped KKL of axis ``name`` (one of :data:`AXES`)."""
    return checkpoint_dir() / f"kkl_pan_tilt_{name}.safetensors"


def reference_world():
    """The world the shipped pair was trained in: ``luma`` at its 30 m, a level LED, the
    pan-tilt head with its quad."""
    from ledsim.loop.world_part import WorldPart

    return WorldPart(link="luma", gimbal="pan-tilt").world_config()


@functools.cache
def reference_axes() -> tuple[AxisRatioModel, AxisRatioModel]:
    """Each axis's system in :func:`reference_world` (its head's model fitted there)."""
    from ledsim.physics.head_system import HeadSystem

    head = HeadSystem(reference_world()).model()
    return tuple(AxisRatioModel(head, a) for a in range(len(AXES)))


def head_kkl(model: HeadModel) -> PerAxis:
    """The shipped KKL of a pan-tilt run whose head's model is ``model``: each axis's
    observer, checked against that axis's system, on its ratios of the run's powers."""
    axes = [AxisRatioModel(model, a) for a in range(len(AXES))]
    observers = []
    for system, name in zip(axes, AXES, strict=True):
        path = shipped_axis(name)
        if not path.is_file():
            raise LedsimError(f"no shipped KKL for the pan-tilt's {name}: train it with "
                              "`python scripts/train_pan_tilt.py`")
        observers.append(ckpt.load(path, system, name=f"kkl-{name}"))
    return PerAxis(model, observers, lambda y: [m.split(y) for m in axes], "kkl")
