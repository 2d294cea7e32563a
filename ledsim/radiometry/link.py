"""A physical LED link: transmitter, water and receiver, turned into the constants of
the paper's power law and into the receiver's noise.

The paper's law P = a exp(-b d) / d^2 I~(theta) g(phi) is already radiometric. With
the hardware it reads

    P = I0 A T exp(-K d) / d^2 cos(theta)^m g(phi)            [W on the detector]

    I0 = P_tx (m + 1) / (2 pi)   the LED's peak intensity              [W/sr]
    A, T                         collection area [m^2], filter transmission [-]
    K                            the water's effective attenuation     [1/m]
    g(phi)                       the receiver optics' response, 1 on axis

so ``a = I0 A T`` and ``b = K`` (:meth:`RadiometricLink.constants`). The noise is the
detector's (:meth:`~ledsim.radiometry.hardware.Detector.noise_terms`) with sunlight that
falls with depth:

    P_bg = L A T Omega dlambda,    L = E_s exp(-K_d z) / pi x HORIZONTAL_RADIANCE_RATIO

E_s the surface's downwelling spectral irradiance [W m^-2 nm^-1], K_d the water's
diffuse attenuation, z the receiver's depth, Omega the field of view's solid angle and
dlambda the filter's band. The pointing channel samples once a control period (noise
bandwidth 1 / (2 Te)); the data channel runs on-off keyed at the bit rate (R_b / 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ledsim.constants import LinkConstants, ReceiverResponse
from ledsim.errors import LedsimError
from ledsim.radiometry.hardware import Detector, ReceiverOptics, Transmitter
from ledsim.radiometry.water import Water
from observer.noise import Digitiser, MeasurementNoise

#: Horizontal radiance over the downwelling irradiance's equivalent radiance E_d / pi
#: [-]: the upper ocean's radiance distribution peaks near the zenith; looking sideways
#: a receiver sees about a third of it (Mobley 1994, ch. 1 and 10).
HORIZONTAL_RADIANCE_RATIO = 0.3


@dataclass(frozen=True)
class RadiometricLink:
    """One physical link: its hardware, its water and where the receiver is.

    Attributes:
        name: the preset's name.
        transmitter, detector, optics: the hardware.
        water: the water between them.
        depth: the receiver's depth [m] (sets the daylight it sees).
        surface_irradiance: daylight's downwelling spectral irradiance just below the
            surface at the link's wavelength [W m^-2 nm^-1] (0: night, or deep water;
            about 1.5 for a clear sky at noon, ASTM G173).
    """

    name: str
    transmitter: Transmitter
    detector: Detector
    optics: ReceiverOptics
    water: Water
    depth: float = 10.0
    surface_irradiance: float = 0.0

    def __post_init__(self) -> None:
        for key, hi, unit in (("depth", 11000.0, "m"),
                              ("surface_irradiance", 5.0, "W m^-2 nm^-1")):
            value = getattr(self, key)
            if not (math.isfinite(value) and 0 <= value <= hi):
                raise LedsimError(f"{key}={value!r} is not allowed: must be in "
                                  f"[0, {hi:g}] {unit}")

    @property
    def water_at_led(self) -> Water:
        """The water at the LED's wavelength."""
        return self.water.at_wavelength(self.transmitter.wavelength)

    @property
    def attenuation(self) -> float:
        """K: the water's effective attenuation for this beam and field of view, at the
        LED's wavelength [1/m]."""
        return self.water_at_led.effective_attenuation(
            min(self.transmitter.half_power_angle, self.optics.field_of_view))

    @property
    def power_scale(self) -> float:
        """a = I0 A T [W m^2]: the received power at 1 m on both axes, before the water."""
        o = self.optics
        return (self.transmitter.on_axis_intensity * o.collection_area
                * o.filter_transmission)

    @property
    def response(self) -> ReceiverResponse:
        """g(phi): a Gaussian of half-power half-angle ``optics.field_of_view`` (the
        paper's two-Gaussian form with no shoulder)."""
        return ReceiverResponse(a1=1.0, b1=0.0, c1=self.optics.field_of_view
                                / math.sqrt(math.log(2.0)), a2=0.0, b2=0.0, c2=1.0)

    @property
    def background_power(self) -> float:
        """Daylight on the detector, P_bg [W]."""
        o = self.optics
        radiance = (self.surface_irradiance * math.exp(-self.water_at_led.diffuse_attenuation()
                                                        * self.depth)
                    / math.pi * HORIZONTAL_RADIANCE_RATIO)
        return (radiance * o.collection_area * o.solid_angle * o.filter_bandwidth
                * o.filter_transmission)

    def noise(self, bandwidth: float, n_output: int = 2, scale: float = 1.0,
              digitised: bool = True) -> MeasurementNoise:
        """The receiver's noise over ``bandwidth`` [Hz], in watts on the detector, with
        the ADC (``digitised``) or without (the data channel's slicer)."""
        floor, shot = self.detector.noise_terms(self.background_power, bandwidth)
        return MeasurementNoise(math.sqrt(floor), n_output, scale, shot,
                                self.detector.digitiser if digitised else None)

    def constants(self, distance: float, base: LinkConstants | None = None) -> LinkConstants:
        """The paper's constants with this link's: a, b, the LED's half-power angle,
        g(phi) and the pointing channel's noise floor (``base``: the rest; default the
        paper's)."""
        base = LinkConstants() if base is None else base
        floor = self.noise(1.0 / (2.0 * base.Te)).nominal_std
        return base.with_(distance=distance, power_scale=self.power_scale,
                          attenuation=self.attenuation,
                          led_half_angle=self.transmitter.half_power_angle,
                          measurement_noise_var=floor**2, receiver=self.response,
                          link=self)

    @classmethod
    def from_dict(cls, d: dict) -> RadiometricLink:
        """The link from :func:`dataclasses.asdict` data (a checkpoint's metadata)."""
        d = dict(d)
        detector = dict(d["detector"])
        detector["digitiser"] = Digitiser(**detector["digitiser"])
        return cls(name=d["name"], transmitter=Transmitter(**d["transmitter"]),
                   detector=Detector(**detector), optics=ReceiverOptics(**d["optics"]),
                   water=Water(**d["water"]), depth=d.get("depth", 10.0),
                   surface_irradiance=d.get("surface_irradiance", 0.0))


def constants_from_dict(d: dict) -> LinkConstants:
    """:meth:`LinkConstants.from_dict` for the constants of either link: the paper's
    bench, or a physical link (``link`` rebuilt as a :class:`RadiometricLink`)."""
    d = dict(d)
    link = d.pop("link", None)
    c = LinkConstants.from_dict(d)
    return c if link is None else c.with_(link=RadiometricLink.from_dict(link))
