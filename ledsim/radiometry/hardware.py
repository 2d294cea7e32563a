"""The link's hardware: the LED transmitter, the detector and the receiver's optics.

Every figure carries its unit, and the catalogue below says where it comes from. A
figure a maker does not publish is a representative part's datasheet value, named as
such; ``docs/link.md`` lists which figures are published and which are assumed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ledsim.errors import LedsimError
from observer.noise import Digitiser

#: Elementary charge [C].
ELEMENTARY_CHARGE = 1.602176634e-19


def _check(owner: str, checks) -> None:
    for name, value, ok, allowed in checks:
        if not (ok and math.isfinite(value)):
            raise LedsimError(f"{owner} {name}={value!r} is not allowed: must be {allowed}")


@dataclass(frozen=True)
class Transmitter:
    """The LED array.

    Attributes:
        optical_power: total radiant power emitted [W].
        wavelength: peak wavelength [nm].
        half_power_angle: angle off the axis where the intensity halves [rad]; sets the
            Lambertian order m of I(theta) = I0 cos(theta)^m.
        source: where the figures come from.
    """

    optical_power: float
    wavelength: float
    half_power_angle: float
    source: str = ""

    def __post_init__(self) -> None:
        _check("transmitter", [
            ("optical_power", self.optical_power, self.optical_power > 0, "> 0 W"),
            ("wavelength", self.wavelength, 350 <= self.wavelength <= 700, "in [350, 700] nm"),
            ("half_power_angle", self.half_power_angle,
             0 < self.half_power_angle < math.pi / 2, "in (0, pi/2) rad")])

    @property
    def lambertian_order(self) -> float:
        """m with cos(half_power_angle)^m = 1/2 [-]."""
        return -math.log(2.0) / math.log(math.cos(self.half_power_angle))

    @property
    def on_axis_intensity(self) -> float:
        """I0 = P (m + 1) / (2 pi) [W/sr]: the generalised Lambertian's peak."""
        return self.optical_power * (self.lambertian_order + 1) / (2 * math.pi)


@dataclass(frozen=True)
class Detector:
    """The photodetector and its amplifier, referred to the optical power on it.

    Attributes:
        kind: ``pin`` (silicon photodiode), ``apd`` (avalanche photodiode) or ``pmt``
            (photomultiplier tube).
        area: active area [m^2].
        responsivity: photocurrent per optical watt at unity gain [A/W] (a PMT's
            photocathode radiant sensitivity).
        gain: internal multiplication M [-] (1 for a PIN).
        excess_noise: excess noise factor F of the multiplication [-] (1 for a PIN).
        dark_current: dark current referred to the input of the gain [A].
        amplifier_noise: the amplifier's input current noise density, after the gain
            [A/sqrt(Hz)] (thermal noise of the transimpedance stage).
        digitiser: the ADC and the gain control behind the amplifier, in optical watts
            on the detector.
        source: where the figures come from.
    """

    kind: str
    area: float
    responsivity: float
    gain: float
    excess_noise: float
    dark_current: float
    amplifier_noise: float
    digitiser: Digitiser
    source: str = ""

    def __post_init__(self) -> None:
        if self.kind not in ("pin", "apd", "pmt"):
            raise LedsimError(f"detector kind {self.kind!r} is not allowed: choose one of "
                              "pin, apd, pmt")
        _check("detector", [
            ("area", self.area, self.area > 0, "> 0 m^2"),
            ("responsivity", self.responsivity, 0 < self.responsivity <= 1, "in (0, 1] A/W"),
            ("gain", self.gain, self.gain >= 1, ">= 1"),
            ("excess_noise", self.excess_noise, self.excess_noise >= 1, ">= 1"),
            ("dark_current", self.dark_current, self.dark_current >= 0, ">= 0 A"),
            ("amplifier_noise", self.amplifier_noise, self.amplifier_noise >= 0,
             ">= 0 A/sqrt(Hz)")])

    def noise_terms(self, background: float, bandwidth: float) -> tuple[float, float]:
        """(floor variance [W^2], shot coefficient [W]) of the optical-equivalent noise
        over ``bandwidth`` [Hz] with ``background`` [W] of ambient light on the detector:

            var(P) = 2 q F (R (P + P_bg) + I_d) B / R^2 + (i_n / M)^2 B / R^2

        the shot noise of the signal, the background and the dark current, multiplied
        with excess noise F, and the amplifier's noise referred through the gain M.
        """
        q, f, r = ELEMENTARY_CHARGE, self.excess_noise, self.responsivity
        floor = (2 * q * f * (r * background + self.dark_current)
                 + (self.amplifier_noise / self.gain) ** 2) * bandwidth / r**2
        return floor, 2 * q * f * bandwidth / r


@dataclass(frozen=True)
class ReceiverOptics:
    """What sits in front of the detector.

    Attributes:
        collection_area: the entrance aperture that gathers light onto the detector
            [m^2] (a lens's or concentrator's; the detector's own area without one).
        field_of_view: half-angle where the response halves [rad]; the receiver's
            angular response g(phi) is the Gaussian with that half-power angle.
        filter_transmission: the optical band-pass filter's transmission in band [-].
        filter_bandwidth: its pass band [nm] (what lets background light in).
        source: where the figures come from.
    """

    collection_area: float
    field_of_view: float
    filter_transmission: float = 0.9
    filter_bandwidth: float = 40.0
    source: str = ""

    def __post_init__(self) -> None:
        _check("receiver optics", [
            ("collection_area", self.collection_area, self.collection_area > 0, "> 0 m^2"),
            ("field_of_view", self.field_of_view, 0 < self.field_of_view < math.pi / 2,
             "in (0, pi/2) rad"),
            ("filter_transmission", self.filter_transmission,
             0 < self.filter_transmission <= 1, "in (0, 1]"),
            ("filter_bandwidth", self.filter_bandwidth, self.filter_bandwidth > 0, "> 0 nm")])

    @property
    def solid_angle(self) -> float:
        """The field of view's solid angle 2 pi (1 - cos(field_of_view)) [sr]."""
        return 2 * math.pi * (1 - math.cos(self.field_of_view))


_S8664 = ("Hamamatsu S8664-1010 class Si APD datasheet (10 mm diameter, 0.24 A/W at "
          "M = 1 and 420 nm, M = 50, excess-noise index 0.2: F = 50^0.2; the reverse "
          "bias sets M from 50 down to a few)")
_S3590 = ("Hamamatsu S3590-08 class Si PIN datasheet (10 x 10 mm, about 0.3 A/W at "
          "470 nm)")
_H10721 = ("Hamamatsu H10721-210 class PMT module datasheet (8 mm photocathode, about "
           "0.1 A/W cathode sensitivity at 450 nm, gain 2e6, F about 1.3; the control "
           "voltage turns the gain down about three decades)")

#: Conversions averaged into one pointing sample: an ADC at 1 MS/s over the 10 ms
#: control period (the modem's receiver digitises the data at that rate).
CONVERSIONS = 10_000

#: The detector's own gain turned down above the ADC's ranges, in 6 dB steps (the
#: receiver's headroom close in, ``Digitiser.headroom_steps``): a PMT's control voltage
#: about three decades (2^10), an APD's bias from M = 50 to about 3 (2^4); a PIN has no
#: gain to turn (and never fills its scale: aquaoptical's peak at 1 m is 3 % of it).
#: Enough that no preset's bare detector clips down to 1 m in any water
#: (``scripts/saturation_ranges.py``).
PMT_HEADROOM, APD_HEADROOM = 10, 4

#: Representative detectors (the makers of the modems do not publish their parts).
DETECTORS = {
    "si-apd": Detector("apd", math.pi * 0.005**2, 0.24, 50.0, 50.0**0.2, 1e-10, 2e-12,
                       Digitiser(12, 1e-4, 8, conversions=CONVERSIONS,
                                 headroom_steps=APD_HEADROOM), _S8664),
    "si-pin": Detector("pin", 1e-4, 0.3, 1.0, 1.0, 2e-9, 2e-12,
                       Digitiser(12, 1e-2, 8, conversions=CONVERSIONS), _S3590),
    "pmt": Detector("pmt", math.pi * 0.004**2, 0.1, 2e6, 1.3, 5e-15, 10e-12,
                    Digitiser(12, 1e-6, 8, conversions=CONVERSIONS,
                              headroom_steps=PMT_HEADROOM), _H10721),
}
