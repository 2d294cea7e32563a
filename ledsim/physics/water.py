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
from .disturbance_base import Disturbance
from .world import LinkWorld


@dataclass
class WaterCurrent(Disturbance):
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

    def __post_init__(self):
        self.reset(self.seed)

    def reset(self, seed: int) -> None:
        self.seed = seed
        self._rng = np.random.default_rng(seed)
        self._g = np.zeros(3)
        self._last_t = None

    def apply(self, world: LinkWorld, t: float) -> None:
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._last_t = t
        if dt > 0 and self.gust > 0:
            a = math.exp(-dt / self.gust_time)
            self._g = a * self._g + self.gust * math.sqrt(1 - a * a) * \
                self._rng.standard_normal(3) * np.array([1.0, 1.0, 0.3])
        steady = self.speed * np.array([math.cos(self.heading), math.sin(self.heading), 0.0])
        world.set_current(steady + self._g)


@dataclass
class Waves(Disturbance):
    """Surface waves: the wave-orbital velocity at the vehicle's depth (linear, deep
    water), the ordinary sea state an AUV works in. A wave of height H and period T has
    angular frequency w = 2 pi / T and wavenumber k = w^2 / g; at depth z its water
    moves on circles of radius (H / 2) exp(-k z), so the velocity is

        u = (H / 2) w exp(-k z) (cos(w t) along ``heading``, sin(w t) up)

    The hull's drag turns it into sway (across the hull) and, through the fins aft of
    its centre, yaw.

    Attributes:
        height: wave height H, crest to trough [m].
        period: wave period T [s].
        heading: direction the waves travel in the horizontal plane [rad] (0 = +x).
        depth: the vehicle's depth below the surface [m].
        hold: 1 = the vehicle keeps station, 0 = it drifts with the water.
    """

    changes_model = True  # the medium velocity is a model option

    height: float = 1.0
    period: float = 8.0
    heading: float = math.pi / 2
    depth: float = 10.0
    hold: float = 1.0

    @property
    def amplitude(self) -> float:
        """The orbital velocity's amplitude at the vehicle's depth [m/s]."""
        w = 2 * math.pi / self.period
        return 0.5 * self.height * w * math.exp(-w * w / GRAVITY * self.depth)

    def apply(self, world: LinkWorld, t: float) -> None:
        w = 2 * math.pi / self.period
        a = self.amplitude
        horizontal = a * math.cos(w * t)
        world.set_current((horizontal * math.cos(self.heading),
                           horizontal * math.sin(self.heading), a * math.sin(w * t)))
