"""The light around the receiver: sunlight that waves focus into flicker, and the
fading (scintillation) of the LED's own light in turbulent or bubbly water.

Both act on the pointing samples through :class:`~ledsim.physics.world.LinkWorld`'s
``light_gain`` (a factor on each photodiode's received LED power, which the data
channel sees too) and ``light_noise`` (watts added to each sample), which the sensor
applies after the geometry (None: no such light); neither touches the physics. The
estimators are not told: their noise model stays the link's at night in still water.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ledsim.physics.disturbance_base import DisturbanceError, SeededDisturbance
from ledsim.physics.world import LinkWorld


def _pair(rng: np.random.Generator, n: int, correlation: float) -> np.ndarray:
    """n standard normals whose pairwise correlation is ``correlation``."""
    common = rng.standard_normal()
    own = rng.standard_normal(n)
    return math.sqrt(correlation) * common + math.sqrt(1.0 - correlation) * own


def window_share(time: float, window: float) -> float:
    """The variance of a process with exponential correlation (time ``time`` [s])
    averaged over ``window`` [s], as a share of its own [-]."""
    x = window / time
    return 2.0 / (x * x) * (x - 1.0 + math.exp(-x)) if x > 1e-9 else 1.0


@dataclass
class SunlightFlicker(SeededDisturbance):
    """Daylight on the receiver, focused by the surface's waves into flicker.

    Sunlight reaches the detector through its filter and field of view as the link's
    background power at the receiver's depth (``RadiometricLink.background_power``:
    Kirk's diffuse attenuation, a third of the zenith radiance sideways). The pointing
    channel demodulates the LED's modulation, so the sunlight itself and its slow
    flicker are rejected, but not their shot noise: each sample gains the shot noise of
    the background at that instant, ``P_bg(t) = P_bg F(t)``. F is log-normal with mean
    1 and coefficient of variation ``contrast``, narrow-band around ``frequency``: the
    caustics of the waves' lensing (Darecki, Stramski and Sokolski, J. Geophys. Res.
    116, C00H09, 2011: under a clear sky near the surface the irradiance's coefficient
    of variation reaches 0.5 and more, its dominant frequency 1-3 Hz, both falling with
    depth). Needs a physical link (``--link``): the paper's bench has no detector.

    Attributes:
        irradiance: the downwelling spectral irradiance just below the surface at the
            LED's wavelength [W m^-2 nm^-1] (about 1.5 for a clear sky at noon, ASTM
            G173 through the surface).
        contrast: the flicker's coefficient of variation at the receiver [-] (None:
            0.5 exp(-depth / 3 m), the order of Darecki et al.'s profiles).
        frequency: the flicker's dominant frequency [Hz] (None: 2.5 Hz at the surface
            falling to 0.5 Hz by 15 m, as theirs).
        seed: seed of the flicker.
    """

    irradiance: float = 1.5
    contrast: float | None = None
    frequency: float | None = None
    seed: int = 0

    def restart(self) -> None:
        self._z = 0j
        self._terms = None

    def contrast_at(self, depth: float) -> float:
        """The coefficient of variation at ``depth`` [m]."""
        return 0.5 * math.exp(-depth / 3.0) if self.contrast is None else self.contrast

    def frequency_at(self, depth: float) -> float:
        """The dominant frequency at ``depth`` [m] [Hz]."""
        if self.frequency is not None:
            return self.frequency
        return 0.5 + 2.0 * math.exp(-depth / 5.0)

    #: It needs a physical link's detector (the run's validation asks before any work).
    needs_receiver = True
    NO_RECEIVER = ("flicker needs a physical link's receiver (--link luma, aquaoptical or "
                   "bluecomm-200): the paper's bench has none")

    def _setup(self, world: LinkWorld):
        link = world.config.constants.link
        if link is None:
            raise DisturbanceError(self.NO_RECEIVER)
        depth = world.config.depth
        lit = dataclasses.replace(link, depth=depth, surface_irradiance=self.irradiance)
        bandwidth = 1.0 / (2.0 * world.config.constants.Te)
        # the floor's variance grows linearly with the background: its share per watt
        per_watt = (link.detector.noise_terms(1.0, bandwidth)[0]
                    - link.detector.noise_terms(0.0, bandwidth)[0])
        cv = self.contrast_at(depth)
        self.background_power = lit.background_power
        self._terms = (per_watt * lit.background_power, math.sqrt(math.log1p(cv * cv)),
                       self.frequency_at(depth))

    def apply(self, world: LinkWorld, t: float) -> None:
        if self._terms is None:
            self._setup(world)
        variance, sigma, f = self._terms
        # a complex Ornstein-Uhlenbeck envelope (unit variance, correlation time 1 / f)
        # turning at f: narrow-band around f
        kick = complex(*self._rng.standard_normal(2)) * math.sqrt(0.5)
        dt = self.elapsed(t)
        if dt is None:
            self._z = kick
        elif dt > 0:
            a = math.exp(-dt * f)
            self._z = a * self._z + math.sqrt(1 - a * a) * kick
        phase = 2 * math.pi * f * t
        x = math.sqrt(2) * (self._z * complex(math.cos(phase), math.sin(phase))).real
        flicker = math.exp(sigma * x - 0.5 * sigma * sigma)  # F(t): mean 1
        self.flicker = flicker
        world.light_noise = self._rng.standard_normal(len(world.ids.photodiode_sites)) * math.sqrt(
            variance * flicker)


@dataclass
class Scintillation(SeededDisturbance):
    """Log-normal fading of the LED's light: turbulence (temperature and salinity
    microstructure) or bubbles between the LED and the receiver.

    The received power is I = I0 exp(L), L normal with mean -s^2 / 2 and variance
    s^2 = ln(1 + ``index``), so that its mean is I0 and its scintillation index
    var(I) / E[I]^2 is ``index``. The fading decorrelates in ``time``; a pointing sample
    is the mean of a control period's conversions, so its fading's variance is shrunk
    by the window's share (:func:`window_share`), and successive samples correlate by
    exp(-Te / time). The photodiodes, millimetres apart, fade together with
    ``correlation``. Sources: Jamali et al., IEEE Trans. Commun. 66(10), 2018 (the
    index from 0.01 in weak turbulence to above 1 with bubbles, the log-normal fitting
    weak turbulence up to about 0.4; coherence times of 1e-5 to 1e-2 s).

    Attributes:
        index: the scintillation index of the received power [-] (0.1: moderate).
        time: the fading's correlation time [s].
        correlation: the correlation of the photodiodes' fading [-].
        seed: seed of the fading.
    """

    index: float = 0.1
    time: float = 0.003
    correlation: float = 0.99
    seed: int = 0

    def restart(self) -> None:
        self._x = None

    def apply(self, world: LinkWorld, t: float) -> None:
        Te = world.config.constants.Te
        s2 = math.log1p(self.index * window_share(self.time, Te))
        n = len(world.ids.photodiode_sites)
        dt = self.elapsed(t)
        if self._x is None:
            self._x = _pair(self._rng, n, self.correlation)
        elif dt is not None and dt > 0:
            rho = math.exp(-dt / self.time)
            self._x = rho * self._x + math.sqrt(1 - rho * rho) * _pair(
                self._rng, n, self.correlation)
        world.light_gain = np.exp(math.sqrt(s2) * self._x - 0.5 * s2)
