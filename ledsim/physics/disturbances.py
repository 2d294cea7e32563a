"""Disturbances acting on the link, applied once per control period before physics.

Each is a small dataclass with its knobs as fields, ``reset(seed)`` at the start of a
run and ``apply(world, t)`` (t in s) once per control period; it acts only through
:class:`~ledsim.physics.world.LinkWorld`'s methods. :func:`parse_disturbance` builds one
from ``name[:key=value,...]`` (the CLI form).

================  ============================================================
name              what it does
================  ============================================================
vibration         sinusoidal yaw torque and sway force on the AUV hull
current           water current: steady velocity plus random gusts (opt.wind)
waves             linear waves: strip forces along the hull (or one medium velocity)
transmitter       the LED platform sways sideways and rotates (yaw)
occlusion         a plate crosses the line of sight for ``duration`` seconds
kick              an angular-rate impulse to the gimbal or the hull at ``start``
dvl_dropout       the DVL loses bottom lock for ``duration`` s (every ``every`` s)
flicker           daylight's shot noise, flickering as the waves focus it
scintillation     log-normal fading of the LED's light (turbulence, bubbles)
================  ============================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ledsim.keyvalues import parse_key_values
from ledsim.physics.disturbance_base import (  # noqa: F401 (aliases: the parser's error)
    Disturbance,
    DisturbanceError,
)
from ledsim.physics.flow import WaterCurrent, Waves
from ledsim.physics.light import Scintillation, SunlightFlicker
from ledsim.physics.world import LinkWorld


@dataclass
class HullVibration(Disturbance):
    """Hull vibration: ``torque cos(2 pi f t)`` about z and ``force cos(2 pi f t)`` along y.

    Cosine, so the hull's velocity oscillates about zero (a sine started at rest would
    add a steady drift of force / (m 2 pi f)).

    Attributes:
        frequency: vibration frequency f [Hz].
        torque: yaw torque amplitude on the hull [N m].
        force: sway force amplitude on the hull [N].
    """

    frequency: float = 2.0
    torque: float = 0.5
    force: float = 0.0

    def apply(self, world: LinkWorld, t: float) -> None:
        s = math.cos(2 * math.pi * self.frequency * t)
        world.add_hull_wrench(force=(0.0, self.force * s, 0.0), torque=(0.0, 0.0, self.torque * s))


@dataclass
class TransmitterMotion(Disturbance):
    """The LED platform sways sideways, yaws sinusoidally and drifts along the link.

    Attributes:
        sway: lateral (y) amplitude [m].
        frequency: motion frequency [Hz].
        yaw: yaw amplitude of the LED axis [rad] (changes theta).
        drift: speed away from the receiver along the link [m/s] (changes d; negative
            comes closer), until ``drift_until``.
        drift_until: time the drift stops [s].
    """

    sway: float = 0.005
    frequency: float = 0.5
    yaw: float = 0.0
    drift: float = 0.0
    drift_until: float = 3600.0

    def apply(self, world: LinkWorld, t: float) -> None:
        w = 2 * math.pi * self.frequency
        along = self.drift * min(t, self.drift_until)
        pos = world.transmitter_home + np.array([along, self.sway * math.sin(w * t), 0.0])
        vel = np.array([self.drift if t < self.drift_until else 0.0,
                        self.sway * w * math.cos(w * t), 0.0])
        world.set_transmitter(pos, vel, yaw=self.yaw * math.sin(w * t) if self.yaw else None)


@dataclass
class Occlusion(Disturbance):
    """A plate slides down through the line of sight.

    Attributes:
        start: time the plate's leading edge reaches the beam [s].
        duration: time the beam centre stays covered [s].
    """

    start: float = 1.0
    duration: float = 0.5

    def apply(self, world: LinkWorld, t: float) -> None:
        half = world.occluder_half_size
        speed = 2 * half / self.duration  # covers the beam centre for `duration`
        mid = world.link_midpoint()
        z = mid[2] + half - speed * (t - self.start)
        z = min(max(z, mid[2] - 3 * half), mid[2] + 3 * half)
        world.set_occluder([mid[0], mid[1], z])

    def covers(self, t: float) -> bool:
        """Whether the plate is over the beam centre at time t (for the flags)."""
        return self.start <= t < self.start + self.duration

    @property
    def event_end(self) -> float:
        return self.start + self.duration


#: Allowed values of every key: (low, high, unit, low end excluded). Wide enough for any
#: physical test of a small AUV, narrow enough that MuJoCo stays finite.
RANGES = {
    "frequency": (0.0, 50.0, "Hz", True),  # Nyquist of the 10 ms control period
    "torque": (-100.0, 100.0, "N m", False),
    "force": (-1000.0, 1000.0, "N", False),
    "speed": (0.0, 5.0, "m/s", False),
    "heading": (-2 * math.pi, 2 * math.pi, "rad", False),
    "gust": (0.0, 2.0, "m/s", False),
    "gust_time": (0.0, 100.0, "s", True),
    "hold": (0.0, 1.0, "(0 or 1)", False),
    "hull": (0.0, 1.0, "(0 or 1)", False),
    "seed": (0, 2**32 - 1, "", False),
    "sway": (-5.0, 5.0, "m", False),  # a second vehicle metres away sways by dm
    "yaw": (-math.pi / 2, math.pi / 2, "rad", False),
    "start": (0.0, 3600.0, "s", False),
    "rate": (-50.0, 50.0, "rad/s", False),
    "duration": (0.0, 3600.0, "s", True),
    "drift": (-0.5, 0.5, "m/s", False),
    "drift_until": (0.0, 3600.0, "s", False),
    "height": (0.0, 20.0, "m", False),
    "period": (1.0, 30.0, "s", False),
    "depth": (1.0, 500.0, "m", False),
    "strips": (0, 64, "", False),
    "irradiance": (0.0, 5.0, "W m^-2 nm^-1", False),
    "contrast": (0.0, 3.0, "", False),
    "index": (0.0, 1.0, "(scintillation index)", True),
    "time": (1e-5, 10.0, "s", False),
    "correlation": (0.0, 1.0, "", False),
    "sea_depth": (0.0, 11000.0, "m (0: deep water)", False),
    "every": (0.0, 3600.0, "s", False),
}
#: Keys that take a word: the axis a kick turns the hull about.
CHOICES = {"axis": ("yaw", "pitch", "roll")}

@dataclass
class Kick(Disturbance):
    """An angular-rate impulse at time ``start``: the gimbal (``hull=0``) or the AUV
    (``hull=1``) suddenly turns ``rate`` faster about ``axis``, as when the vehicle is
    struck; strong enough by default to throw the receiver out of the observers' domain.

    Attributes:
        start: time of the impulse [s].
        rate: added angular rate [rad/s].
        hull: 0 = the gimbal hinge, 1 = the hull.
        axis: the hull's axis, in its own frame: ``yaw`` (about its vertical, the one
            the gimbal turns about), ``pitch`` (about its sideways axis: the line of
            sight tilts out of the gimbal's plane) or ``roll`` (about its length: the
            line of sight barely moves). The gimbal's hinge turns in yaw only.
    """

    start: float = 3.0
    rate: float = 8.0
    hull: float = 0.0
    axis: str = "yaw"

    def __post_init__(self):
        if self.axis != "yaw" and not self.hull:
            raise DisturbanceError(f"kick.axis={self.axis} is not allowed with hull=0: the "
                                   "gimbal's hinge turns in yaw only; use hull=1 to kick "
                                   f"the hull in {self.axis}")
        self._done = False

    def reset(self, seed: int) -> None:
        self._done = False

    def apply(self, world: LinkWorld, t: float) -> None:
        if not self._done and t >= self.start:
            world.add_angular_rate(self.rate, hull=bool(self.hull), axis=self.axis)
            self._done = True

    @property
    def event_end(self) -> float:
        return self.start


@dataclass
class DvlDropout(Disturbance):
    """The DVL loses bottom lock (a soft seabed, a steep slope, the vehicle too high):
    no velocity pings from ``start`` for ``duration`` s, again every ``every`` s (0:
    once). The navigation coasts on the IMU and the acoustic fixes meanwhile.

    Attributes:
        start: time the first dropout begins [s].
        duration: how long each lasts [s].
        every: time from one dropout's start to the next's [s] (0: only one).
    """

    start: float = 2.0
    duration: float = 5.0
    every: float = 0.0

    def __post_init__(self):
        if self.every and self.every <= self.duration:
            raise DisturbanceError(f"dvl_dropout.every={self.every:g} is not allowed: must "
                                   f"be 0 (once) or longer than duration={self.duration:g} s")

    def lost(self, t: float) -> bool:
        """Whether the DVL is without bottom lock at ``t`` [s]."""
        if t < self.start:
            return False
        since = t - self.start
        if self.every:
            since = math.fmod(since, self.every)
        return since < self.duration

    def apply(self, world: LinkWorld, t: float) -> None:
        world.dvl_bottom_lock = not self.lost(t)


DISTURBANCES = {
    "vibration": HullVibration,
    "current": WaterCurrent,
    "waves": Waves,
    "transmitter": TransmitterMotion,
    "occlusion": Occlusion,
    "kick": Kick,
    "dvl_dropout": DvlDropout,
    "flicker": SunlightFlicker,
    "scintillation": Scintillation,
}


def parse_disturbance(text: str) -> Disturbance:
    """``"vibration:frequency=3,torque=0.2"`` -> HullVibration(frequency=3, torque=0.2)."""
    name, _, args = text.partition(":")
    if name not in DISTURBANCES:
        raise DisturbanceError(f"unknown disturbance {name!r}: choose from "
                               f"{', '.join(DISTURBANCES)}")
    cls = DISTURBANCES[name]
    items = list(filter(None, args.split(",")))
    kwargs = parse_key_values(items, [f.name for f in fields(cls)], name, DisturbanceError,
                              integers=("seed", "strips"), choices=CHOICES)
    texts = dict(i.partition("=")[::2] for i in items)
    for key, v in kwargs.items():
        if key in CHOICES:
            continue
        lo, hi, unit, lo_open = RANGES[key]
        if not (math.isfinite(v) and (lo < v if lo_open else lo <= v) and v <= hi):
            raise DisturbanceError(f"{name}.{key}={texts[key]} is not allowed: must be in "
                                   f"{'(' if lo_open else '['}{lo:.4g}, {hi:.4g}] {unit}"
                                   .rstrip())
    for key in ("hold", "hull"):
        if kwargs.get(key, 0.0) not in (0.0, 1.0):
            raise DisturbanceError(f"{name}.{key}={kwargs[key]!r} is not allowed: must be 0 "
                                   "or 1")
    return cls(**kwargs)


def check_timing(disturbances, seconds: float) -> None:
    """Refuse a transient event that the run would never see (it starts at or after the
    end of a run of ``seconds`` s)."""
    for d in disturbances:
        start = getattr(d, "start", None)
        if start is not None and start >= seconds:
            raise DisturbanceError(f"{type(d).__name__.lower()} starts at {start:g} s, at or "
                                   f"after the end of the {seconds:g} s run")


def check_sea(disturbances, depth: float, transmitter_depth: float | None = None,
              sea_depth: float | None = None) -> None:
    """Refuse waves the run's vehicles cannot be in (:meth:`Waves.check_sea`): their
    trough must pass over the receiver at ``depth`` [m] and the LED at
    ``transmitter_depth`` [m] (None: the receiver's), with room for their size, and they
    must stand in a sea ``sea_depth`` [m] deep (None: their own, else deep water)."""
    for d in disturbances:
        if isinstance(d, Waves):
            d.check_sea(depth, transmitter_depth, sea_depth)
