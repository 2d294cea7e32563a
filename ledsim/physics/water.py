"""The water moving past the vehicle: a current with gusts, and surface waves.

Both act through MuJoCo's medium velocity (``opt.wind``), which the fluid forces of
every body feel; the vehicle's station keeping (:mod:`ledsim.physics.vehicle`) holds it
against them unless ``hold=0``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import GRAVITY
from .disturbance_base import Disturbance, DisturbanceError, SeededDisturbance
from .linear_waves import RegularWave
from .scene import DEFAULT_DEPTH
from .strips import HullStrips, StripCoefficients
from .world import LinkWorld


@dataclass
class WaterCurrent(SeededDisturbance):
    """Water current through MuJoCo's medium velocity (``opt.wind``).

    A free-floating AUV would simply drift away with the water (0.3 m/s is 3 m in 10 s,
    far more than the 8.5 cm link); the vehicle's station keeping
    (:class:`~ledsim.physics.vehicle.Vehicle`, on by default in every scenario) holds it
    on its thrusters, from its own navigation. ``hold=0`` turns that off for the run:
    the hull drifts with the water.

    Attributes:
        speed: steady current speed [m/s].
        heading: direction of the current in the horizontal plane [rad] (0 = +x).
        gust: standard deviation of the gusts [m/s] (Ornstein-Uhlenbeck process).
        gust_time: correlation time of the gusts [s].
        hold: 1 = the vehicle keeps station, 0 = it drifts with the water.
        seed: seed of the gusts.
    """

    changes_model = True  # the medium velocity is a model option

    speed: float = 0.2
    heading: float = math.pi / 2
    gust: float = 0.05
    gust_time: float = 1.0
    hold: float = 1.0
    seed: int = 0

    def restart(self) -> None:
        self._g = np.zeros(3)

    def apply(self, world: LinkWorld, t: float) -> None:
        dt = self.elapsed(t) or 0.0
        if dt > 0 and self.gust > 0:
            a = math.exp(-dt / self.gust_time)
            self._g = a * self._g + self.gust * math.sqrt(1 - a * a) * \
                self._rng.standard_normal(3) * np.array([1.0, 1.0, 0.3])
        steady = self.speed * np.array([math.cos(self.heading), math.sin(self.heading), 0.0])
        world.set_current(steady + self._g)


@dataclass
class Waves(Disturbance):
    """Surface waves: linear (Airy) waves of height H and period T
    (:mod:`ledsim.physics.linear_waves`), the ordinary sea state an AUV works in.

    Two models, by ``strips``:

    - ``strips`` >= 1 (a physical link's default, 12): strip theory
      (:mod:`ledsim.physics.strips`). The hull is cut into slices, each feeling the
      water's acceleration and velocity where it is, which decay with depth below the
      surface and change along the hull: the waves surge, heave and pitch the hull (and
      roll it from the side), and a current (``opt.wind``) acts alongside.
    - ``strips=0`` (the paper's bench's default, so its numbers stay as they were): one
      uniform medium velocity over the whole scene (``opt.wind``), deep water, the
      orbital velocity at the vehicle's depth, u = (H / 2) w exp(-k z) (cos(w t) along
      ``heading``, sin(w t) up). The hull's drag turns it into sway and yaw; it cannot
      pitch the hull.

    Attributes:
        height: wave height H, crest to trough [m].
        period: wave period T [s].
        heading: direction the waves travel in the horizontal plane [rad] (0 = +x, the
            link's direction from the receiver to the LED).
        depth: the vehicle's depth below the still surface [m] (None: the run's
            ``--depth``, 10 m by default).
        hold: 1 = the vehicle keeps station, 0 = it drifts with the water.
        strips: slices of the hull for strip theory (0: the uniform medium velocity;
            None: 12 on a physical link, 0 on the paper's bench).
        sea_depth: the sea's depth under the still surface [m] (0: deep water); finite
            depth changes the dispersion and the decay (cosh and sinh).
    """

    changes_model = True  # the medium velocity is a model option

    height: float = 1.0
    period: float = 8.0
    heading: float = math.pi / 2
    depth: float | None = None
    hold: float = 1.0
    strips: int | None = None
    sea_depth: float = 0.0

    def __post_init__(self):
        if self.depth is not None:
            self._check_sea_depth(self.depth)
        self._strips: HullStrips | None = None

    def _check_sea_depth(self, depth: float) -> None:
        if self.sea_depth and self.sea_depth <= depth:
            raise DisturbanceError(f"waves.sea_depth={self.sea_depth:g} is not allowed: "
                                   f"must be 0 (deep) or deeper than the vehicle's "
                                   f"{depth:g} m")

    @property
    def wave(self) -> RegularWave:
        """The wave as linear theory's :class:`RegularWave`."""
        return RegularWave(self.height, self.period, self.heading,
                           self.sea_depth if self.sea_depth else math.inf)

    @property
    def amplitude(self) -> float:
        """The orbital velocity's amplitude at the vehicle's depth [m/s] (deep water; at
        the default depth when none is set)."""
        w = 2 * math.pi / self.period
        depth = DEFAULT_DEPTH if self.depth is None else self.depth
        return 0.5 * self.height * w * math.exp(-w * w / GRAVITY * depth)

    def strips_in(self, world: LinkWorld) -> int:
        """How many slices the waves use on ``world`` (``strips``, or its default)."""
        if self.strips is not None:
            return int(self.strips)
        return 0 if world.config.constants.link is None else StripCoefficients().strips

    def apply(self, world: LinkWorld, t: float) -> None:
        depth = world.config.depth if self.depth is None else self.depth
        self._check_sea_depth(depth)
        n = self.strips_in(world)
        if n == 0:
            w = 2 * math.pi / self.period
            a = 0.5 * self.height * w * math.exp(-w * w / GRAVITY * depth)
            horizontal = a * math.cos(w * t)
            world.set_current((horizontal * math.cos(self.heading),
                               horizontal * math.sin(self.heading), a * math.sin(w * t)))
            return
        if self._strips is None or self._strips.coefficients.strips != n:
            self._strips = HullStrips(world.model, StripCoefficients(strips=n))
        surface = float(world.initial_hull_pos[2]) + depth
        flow, force, torque = self._strips.wrench(world.model, world.data, self.wave,
                                                  surface, t, world.current)
        world.set_wave_flow(flow)
        world.add_hull_wrench(force, torque)
