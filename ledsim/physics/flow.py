"""The water moving past the vehicle: a current with gusts, and surface waves.

Both act through MuJoCo's medium velocity (``opt.wind``), which the fluid forces of
every body feel; the vehicle's station keeping (:mod:`ledsim.agent.autopilot`) holds it
against them unless ``hold=0``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ledsim.constants import GRAVITY
from ledsim.physics.disturbance_base import Disturbance, DisturbanceError, SeededDisturbance
from ledsim.physics.linear_waves import RegularWave
from ledsim.physics.scene import DEFAULT_DEPTH
from ledsim.physics.strips import HullStrips, StripCoefficients
from ledsim.physics.world import LinkWorld

#: The steepest a wave can stand in deep water, H/L (Michell 1893): steeper, its crest
#: breaks. Over a sea of finite depth h the limit is Miche's (1944), (1/7) tanh(k h),
#: lower, which becomes this one as h grows.
BREAKING_STEEPNESS = 1.0 / 7.0
#: How far above the receiver vehicle's centre a wave's trough must stay [m]: the top of
#: its hull in the shipped scene (``led_link.xml``: the mast antenna reaches 0.15 m above
#: the hull's axis, the vertical fin 0.13 m, the hull itself 0.095 m), so that even the
#: trough passes over the whole vehicle.
HULL_CLEARANCE = 0.15
#: How far above the LED's centre a trough must stay [m]: the top of its housing (a
#: 16 mm radius in ``led_link.xml``), rounded up.
LED_CLEARANCE = 0.02


@dataclass
class WaterCurrent(SeededDisturbance):
    """Water current through MuJoCo's medium velocity (``opt.wind``).

    A free-floating AUV would simply drift away with the water (0.3 m/s is 3 m in 10 s,
    far more than the 8.5 cm link); the vehicle's station keeping
    (:class:`~ledsim.agent.autopilot.Vehicle`, on by default in every scenario) holds it
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

    Only a sea that can exist is built: a wave no steeper than it can stand
    (:meth:`breaking_steepness`), and, against a run's depths (:meth:`check_sea`), a
    trough that passes over the receiver vehicle and the LED.

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
        self._check_steepness()
        self._strips: HullStrips | None = None
        self._checked: tuple | None = None  # the depths check_sea last passed

    def _check_sea_depth(self, depth: float, what: str = "the vehicle's") -> None:
        if self.sea_depth and self.sea_depth <= depth:
            raise DisturbanceError(f"waves.sea_depth={self.sea_depth:g} is not allowed: "
                                   f"must be 0 (deep) or deeper than {what} "
                                   f"{depth:g} m")

    def breaking_steepness(self) -> float:
        """The steepest H/L this wave's period and sea can carry [-]:
        :data:`BREAKING_STEEPNESS` in deep water, Miche's (1/7) tanh(k h) over a sea
        ``sea_depth`` h [m] deep."""
        if not self.sea_depth:
            return BREAKING_STEEPNESS
        return BREAKING_STEEPNESS * math.tanh(self.wave.k * self.sea_depth)

    def _check_steepness(self) -> None:
        """Refuse a wave steeper than it can stand (H/L over :meth:`breaking_steepness`,
        L from the dispersion relation of its period over ``sea_depth``)."""
        if not (math.isfinite(self.period) and self.period > 0):
            raise DisturbanceError(f"waves.period={self.period!r} is not allowed: must be "
                                   "a finite period > 0 s")
        if not (math.isfinite(self.height) and self.height >= 0):
            raise DisturbanceError(f"waves.height={self.height!r} is not allowed: must be "
                                   "a finite height >= 0 m")
        length, limit = self.wave.wavelength, self.breaking_steepness()
        if self.height / length <= limit:
            return
        where = "1/7" if not self.sea_depth else \
            f"tanh(k h)/7 = {limit:.3g}, Miche's limit over sea_depth={self.sea_depth:g} m"
        raise DisturbanceError(
            f"waves: height={self.height:g} m at period={self.period:g} s is steeper than "
            f"a wave can stand: H/L = {self.height / length:.3g} > {where} (L = "
            f"{length:.3g} m): at this period the height is at most "
            f"{limit * length:.3g} m")

    def check_sea(self, depth: float, transmitter_depth: float | None = None,
                  sea_depth: float | None = None) -> None:
        """Refuse a sea the run's vehicles cannot be in: the trough, H/2 below the still
        surface, must pass :data:`HULL_CLEARANCE` [m] over the receiver vehicle (at
        ``depth`` [m], the run's ``--depth``, unless the waves' own ``depth`` says
        otherwise) and :data:`LED_CLEARANCE` [m] over the LED (``transmitter_depth``
        [m]; None: level with the receiver), and the seabed (``sea_depth``) must lie
        below both. The run's ``sea_depth`` [m] (the world's; None: none given) is the
        waves' own where they name none, and their steepness is checked over it. Raises
        :class:`DisturbanceError` naming the limit."""
        if self._checked == (depth, transmitter_depth, sea_depth):
            return
        if sea_depth is not None and not self.sea_depth:
            self.sea_depth = sea_depth  # one sea: the world's depth is the waves' too
            self._check_steepness()
        rise = 0.0 if transmitter_depth is None else depth - transmitter_depth
        if self.depth is None:
            vehicle = (depth, f"--depth {depth:g} m")
            led = (depth - rise, "--transmitter-depth" if transmitter_depth is not None
                   else "--depth")
        else:
            vehicle = (self.depth, f"waves.depth={self.depth:g} m")
            led = (self.depth - rise, "waves.depth and --transmitter-depth")
        led = (led[0], f"{led[0]:g} m ({led[1]})")
        self._check_sea_depth(vehicle[0])
        self._check_sea_depth(led[0], "the LED's")
        trough = 0.5 * self.height
        for (z, where), clearance, what, top in (
                (vehicle, HULL_CLEARANCE, "the vehicle", "its hull's mast and fin reach"),
                (led, LED_CLEARANCE, "the LED", "its housing reaches")):
            if trough > z - clearance:
                raise DisturbanceError(
                    f"waves: height={self.height:g} m puts the trough {trough:g} m below "
                    f"the still surface, too near {what} at {where}: the trough must stay "
                    f"{clearance:g} m above it ({top} {clearance:g} m above its centre), "
                    f"so the height is at most {max(0.0, 2 * (z - clearance)):.3g} m here")
        self._checked = (depth, transmitter_depth, sea_depth)

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
        self.check_sea(world.config.depth, world.config.transmitter_depth,
                       world.config.sea_depth)
        depth = world.config.depth if self.depth is None else self.depth
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
