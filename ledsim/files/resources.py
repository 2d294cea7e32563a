"""Files shipped inside the package (package data), found through importlib.resources.

The MJCF scene sits beside the code that loads it (``ledsim/physics/led_link.xml``); the
trained observers are in ``ledsim/assets/checkpoints``. Nothing is found relative to a
checkout, so an installed wheel works from any directory.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from ledsim.errors import LedsimError


def scene_path() -> Path:
    """The default MJCF scene of the link."""
    return Path(str(files("ledsim.physics") / "led_link.xml"))


def checkpoint_dir() -> Path:
    """Folder of the shipped KKL checkpoints."""
    return Path(str(files("ledsim") / "assets" / "checkpoints"))


def shipped_checkpoint(distance: float, world: str = "closed-form",
                       design: str = "default", noise: float = 1.0) -> Path:
    """Path of the shipped observer (a ``.safetensors`` checkpoint) for a link distance [m].

    Args:
        distance: link distance d [m].
        world: ``"closed-form"`` (trained on the paper's model) or ``"mujoco"``
            (trained on transitions of the MuJoCo world).
        design: ``"default"``, or ``"paper"`` or ``"slow"`` (closed-form only), or
            ``"scheduled"`` (the gain-scheduled KKL), or ``"scheduled-lens"`` (MuJoCo
            only: the gain-scheduled KKL of the physical presets' receiver,
            :func:`ledsim.radiometry.link_presets.kkl_reference_constants`), or ``"lens"``
            (MuJoCo only: the bank's fixed-gain members of that receiver).
        noise: measurement noise it was trained for, over the nominal [-] (MuJoCo
            observers of the bank that serves weak links).
    """
    prefix = {"closed-form": {"default": "kkl", "paper": "kkl_paper", "slow": "kkl_slow",
                              "scheduled": "kkl_scheduled"},
              "mujoco": {"default": "kkl_mujoco", "scheduled": "kkl_mujoco_scheduled",
                         "scheduled-lens": "kkl_mujoco_scheduled_lens",
                         "lens": "kkl_mujoco_lens"}
              }[world][design]
    suffix = "" if noise == 1.0 else f"_noise{noise:g}"
    return checkpoint_dir() / f"{prefix}_d{distance:g}{suffix}.safetensors"


def require_shipped_checkpoint(distance: float, world: str = "closed-form",
                               design: str = "default", noise: float = 1.0) -> Path:
    """:func:`shipped_checkpoint`, or a :class:`LedsimError` that says how to train one."""
    path = shipped_checkpoint(distance, world, design, noise)
    if not path.is_file():
        flag = "" if design == "default" else f" --design {design}"
        how = (f"`ledsim train --distance {distance:g}{flag} --out PATH`"
               if world == "closed-form"
               else f"`ledsim train --world mujoco --distance {distance:g} "
               f"--noise-scale {noise:g} --out PATH`")
        kind = "checkpoint" if world == "closed-form" else "MuJoCo observer"
        raise LedsimError(f"no shipped {kind} for distance {distance:g} m: train one with "
                          f"{how} and pass --checkpoint PATH")
    return path


def shipped_axis(name: str, lens_field_deg: float | None = None) -> Path:
    """The shipped KKL of axis ``name`` (``azimuth`` or ``elevation``), for the bare detector or
    a lens of half-power field ``lens_field_deg`` [deg]."""
    lens = "" if lens_field_deg is None else f"_lens{lens_field_deg:g}"
    return checkpoint_dir() / f"kkl_pan_tilt{lens}_{name}.safetensors"


def pair_paths(path: str | Path) -> dict[str, Path]:
    """A pair's two checkpoints for the name ``path`` (``my.safetensors``:
    ``my_azimuth.safetensors`` and ``my_elevation.safetensors``), by axis."""
    base = Path(path)
    stem = base.stem if base.suffix in (".safetensors", ".pt") else base.name
    return {name: base.with_name(f"{stem}_{name}.safetensors") for name in ("azimuth", "elevation")}
