"""What :class:`~ledsim.envs.link_align.LinkAlignEnv`'s constructor takes: the run's
settings by their spec names, its own options, and ledsim 0.2's positional order; and
the start a reset may be given."""

from __future__ import annotations

import math
from dataclasses import fields

from ledsim.loop.registry import MAX_INITIAL_ANGLE
from ledsim.loop.run_config import WorldPart

#: The run's settings the env takes by name (``LinkAlignEnv(link="luma", depth=20)``):
#: the world part's, and the task's and the estimation's that act on the env.
SPEC_NAMES = (*(f.name for f in fields(WorldPart)), "disturbances", "acquisition", "imu")
#: ledsim 0.2's positional order of the constructor, kept for positional callers.
POSITIONAL = ("scenario", "distance", "noise_scale", "disturbances", "torque_limit",
              "frame_skip", "phi0_range", "render_mode", "width", "height", "camera",
              "integrator", "scene", "imu", "station_keeping", "acquisition", "link",
              "water", "attenuation", "bit_rate", "depth", "transmitter_depth",
              "receiver_dome")


def initial_angle(value) -> float:
    """``options["initial_angle"]`` of :meth:`LinkAlignEnv.reset`, checked [rad]."""
    try:
        a = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"initial_angle {value!r} is not allowed: a number of rad") from None
    if not (math.isfinite(a) and abs(a) <= MAX_INITIAL_ANGLE):
        raise ValueError(f"initial_angle {value!r} is not allowed: must be in "
                         f"[-{MAX_INITIAL_ANGLE:g}, {MAX_INITIAL_ANGLE:g}] rad")
    return a


def constructor_arguments(args: tuple, own: dict, spec: dict) -> tuple[dict, dict]:
    """The env's own options and the spec's names, from its positional ``args`` after
    the scenario (ledsim 0.2's order, :data:`POSITIONAL`: its callers and its pickles),
    ``own`` and ``spec`` by name; a name the env does not take is refused."""
    if args:
        named = dict(zip(POSITIONAL[1:], args, strict=False))
        if len(args) > len(POSITIONAL) - 1 or set(named) & set(spec):
            raise TypeError(f"LinkAlignEnv got {len(args)} positional arguments after "
                            "scenario, or one also by name: name them")
        own = {**own, **{k: named.pop(k) for k in list(named) if k in own}}
        spec = {**named, **spec}
    unknown = sorted(set(spec) - set(SPEC_NAMES))
    if unknown:
        raise TypeError(f"LinkAlignEnv got an unexpected keyword argument {unknown[0]!r}: "
                        f"the run's settings it takes are {', '.join(SPEC_NAMES)}")
    return own, spec
