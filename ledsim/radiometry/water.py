"""The water between the LED and the receiver: absorption, scattering and what they
leave of a beam.

A beam's power falls as exp(-c d), c = a + b the beam attenuation (Beer-Lambert), when
every scattered photon is lost. That is the pessimistic bound: an LED's wide beam
scatters light back in as fast as it scatters it out, at angles up to its own spread,
and the receiver keeps what arrives inside its field of view. Then the power falls
with an effective attenuation between the absorption a and c:

    K = a + b (1 - eta),     eta = share of single scattering within
                                   min(beam half-angle, field-of-view half-angle)

with eta from the Henyey-Greenstein phase function at Petzold's asymmetry g = 0.924
(Haltrin 1999, the usual stand-in for Petzold's particle phase function). It matters in
coastal and harbour water, where b is most of c; in clear water K and c differ by a few
per cent. Narrow (laser) beams or narrow fields of view keep K near c.

The water types are Petzold's measurements at 530 nm as tabulated by Mobley (1994,
*Light and Water*, table 3.10), the values underwater-link studies use (e.g. Kaushal
and Kaddoum, IEEE Access 5, 2017, table 2). At another wavelength
(:meth:`Water.at_wavelength`) the pure water's part of a follows Pope and Fry (Applied
Optics 36(33), 1997) and b scales as 530 nm / lambda (particle scattering's usual
1 / lambda); what the particles and dissolved matter absorb is left as at 530 nm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ledsim.errors import LedsimError, named

#: Pure water's absorption [1/m] every 10 nm from 400 nm (Pope and Fry 1997, table 3).
_PURE_WATER_NM = np.arange(400.0, 610.0, 10.0)
_PURE_WATER_A = np.array([0.00663, 0.00473, 0.00454, 0.00495, 0.00635, 0.00922, 0.00979,
                          0.01060, 0.01270, 0.01500, 0.02040, 0.03250, 0.04090, 0.05070,
                          0.05590, 0.06190, 0.07080, 0.07990, 0.10800, 0.15700, 0.24400])
#: The wavelength of the water types' figures [nm].
REFERENCE_WAVELENGTH = 530.0


def pure_water_absorption(wavelength: float) -> float:
    """Pure water's absorption at ``wavelength`` [nm], 400-600 nm [1/m]."""
    if not 400.0 <= wavelength <= 600.0:
        raise LedsimError(f"wavelength {wavelength!r} nm is not allowed: the water model "
                          "covers 400-600 nm")
    return float(np.interp(wavelength, _PURE_WATER_NM, _PURE_WATER_A))

#: Asymmetry parameter of the Henyey-Greenstein fit to Petzold's phase function [-].
PETZOLD_ASYMMETRY = 0.924
#: Horizontal visibility of a black target times the beam attenuation [-]: V = 4.8 / c
#: (Zaneveld and Pegau, Optics Express 11(23), 2003).
VISIBILITY_CONSTANT = 4.8


@dataclass(frozen=True)
class Water:
    """Inherent optical properties of the water at the link's wavelength.

    Attributes:
        name: the water type.
        absorption: a [1/m].
        scattering: b [1/m].
        source: where the figures come from.
    """

    name: str
    absorption: float
    scattering: float
    source: str = ""
    wavelength: float = REFERENCE_WAVELENGTH

    def __post_init__(self) -> None:
        for key in ("absorption", "scattering"):
            value = getattr(self, key)
            if not (math.isfinite(value) and 0 <= value <= 100):
                raise LedsimError(f"water {key}={value!r} is not allowed: must be in "
                                  "[0, 100] 1/m")

    @property
    def attenuation(self) -> float:
        """Beam attenuation c = a + b [1/m]."""
        return self.absorption + self.scattering

    @property
    def albedo(self) -> float:
        """Single-scattering albedo b / c [-] (0 in water that does not attenuate)."""
        c = self.attenuation
        return self.scattering / c if c > 0 else 0.0

    def forward_share(self, half_angle: float) -> float:
        """Share of single scattering within ``half_angle`` [rad] of the forward
        direction, Henyey-Greenstein at :data:`PETZOLD_ASYMMETRY` [-]."""
        g, mu = PETZOLD_ASYMMETRY, math.cos(min(max(half_angle, 0.0), math.pi))
        return (1 - g * g) / (2 * g) * (1 / (1 - g) - 1 / math.sqrt(1 + g * g - 2 * g * mu))

    def effective_attenuation(self, acceptance_half_angle: float) -> float:
        """K = a + b (1 - eta) [1/m]: the attenuation of a beam whose scattered light
        arrives when within ``acceptance_half_angle`` [rad] (the smaller of the beam's
        and the field of view's half-angles); c when it is 0."""
        return self.absorption + self.scattering * (
            1.0 - self.forward_share(acceptance_half_angle))

    def diffuse_attenuation(self) -> float:
        """K_d [1/m] of downwelling daylight, the sun overhead: sqrt(a^2 + 0.256 a b)
        (Kirk, Limnology and Oceanography 29(2), 1984)."""
        a = self.absorption
        return math.sqrt(a * a + 0.256 * a * self.scattering)

    def at_wavelength(self, wavelength: float) -> Water:
        """This water at ``wavelength`` [nm]: pure water's absorption swapped, b times
        (own wavelength / new one)."""
        if wavelength == self.wavelength:
            return self
        a = max(self.absorption - pure_water_absorption(self.wavelength)
                + pure_water_absorption(wavelength), pure_water_absorption(wavelength))
        return replace(self, absorption=a,
                       scattering=self.scattering * self.wavelength / wavelength,
                       wavelength=wavelength)

    def with_attenuation(self, c: float, wavelength: float | None = None) -> Water:
        """This water's albedo at beam attenuation ``c`` [1/m] (a user-set value),
        measured at ``wavelength`` [nm] (default this water's)."""
        if not (math.isfinite(c) and 0 <= c <= 100):
            raise LedsimError(f"--attenuation {c!r} is not allowed: must be in [0, 100] 1/m")
        albedo = self.albedo
        return replace(self, name=f"{self.name} at c={c:g}/m", absorption=c * (1 - albedo),
                       scattering=c * albedo, source=f"user-set c; albedo of {self.name}",
                       wavelength=self.wavelength if wavelength is None else wavelength)

    @classmethod
    def from_visibility(cls, visibility: float, like: Water) -> Water:
        """Water of horizontal visibility ``visibility`` [m] (c = 4.8 / V) with the
        albedo of ``like``."""
        if not (math.isfinite(visibility) and visibility > 0):
            raise LedsimError(f"visibility {visibility!r} is not allowed: must be > 0 m")
        w = like.with_attenuation(VISIBILITY_CONSTANT / visibility)
        return replace(w, name=f"visibility {visibility:g} m",
                       source=f"V = 4.8 / c (Zaneveld and Pegau 2003); albedo of {like.name}")


_PETZOLD = "Petzold (1972) at 530 nm, tabulated by Mobley (1994) table 3.10"

#: The named water types of ``--water``.
WATER_TYPES = {
    w.name: w for w in (
        Water("pure-sea", 0.053, 0.003, _PETZOLD),
        Water("clear-ocean", 0.114, 0.037, _PETZOLD),
        Water("coastal", 0.179, 0.219, _PETZOLD),
        Water("harbour", 0.366, 1.824, _PETZOLD),
    )
}


def water_named(name: str) -> Water:
    """The water type ``name``; a one-line error naming the allowed ones otherwise."""
    return named(WATER_TYPES, name, "water")
