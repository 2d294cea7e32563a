"""The link presets of ``--link``: the paper's bench and real LED modems built from
their public figures.

Each real preset names what its maker or its authors published (the range, the bit
rate, the water, the LED power) and, for what they did not, the representative part it
assumes. ``scripts/link_presets.py`` computes each one's range at the FEC limit against
its published range (``docs/link.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from ledsim.constants import PAPER_DISTANCE, LinkConstants
from ledsim.errors import LedsimError, named
from ledsim.radiometry.hardware import DETECTORS, ReceiverOptics, Transmitter
from ledsim.radiometry.link import RadiometricLink
from ledsim.radiometry.water import WATER_TYPES, Water, water_named


@dataclass(frozen=True)
class PublishedFigure:
    """A published range: ``bit_rate`` [bit/s] carried to ``range`` [m] in ``water``
    (a water type's name, or ``visibility V m``), and what the preset does with it:
    ``set`` (a parameter was chosen to meet it), ``check`` (computed from the
    hardware, compared) or ``predict`` (held out: computed after the ``set`` one)."""

    range: float
    bit_rate: float
    water: str
    use: str
    source: str


@dataclass(frozen=True)
class LinkPreset:
    """One ``--link``: its hardware (None: the paper's bench), its default distance [m],
    bit rate [bit/s] and water, and its published figures."""

    name: str
    description: str
    transmitter: Transmitter | None = None
    detector: str | None = None
    optics: ReceiverOptics | None = None
    distance: float = PAPER_DISTANCE
    bit_rate: float = 1e3
    water: str = "clear-ocean"
    published: tuple[PublishedFigure, ...] = field(default_factory=tuple)

    @property
    def physical(self) -> bool:
        return self.transmitter is not None

    # What differs between the bench and a physical link, asked of the preset (not of
    # its name) by what builds a run.
    @property
    def kkl_design(self) -> str:
        """The shipped KKL bank's design: the bench's photodiodes, or a lensed head."""
        return "lens" if self.physical else "default"

    @property
    def scheduled_design(self) -> str:
        """The shipped gain-scheduled KKL's design."""
        return "scheduled-lens" if self.physical else "scheduled"

    @property
    def holds_gain_when_driven(self) -> bool:
        """Whether the scheduled KKL holds its gain while the motor works against a load
        (metres of sea: docs/sea.md); the bench keeps the published schedule."""
        return self.physical

    @property
    def kkl_measured_everywhere(self) -> bool:
        """Whether the shipped KKL is measured across the link's whole range
        (docs/link_table.md); on the bench, only between the distances
        ``ledsim.loop.build.estimation.SERVED_DISTANCES``."""
        return self.physical

    @property
    def trains_on_own_receiver(self) -> bool:
        """Whether the shipped KKLs were trained in this link's own world (the bench),
        rather than on the bench's geometry with this link's receiver
        (:func:`kkl_reference_constants`)."""
        return not self.physical

    @property
    def ships_fixed_kkls(self) -> bool:
        """Whether a fixed-gain KKL of each distance is shipped (the bench's, run without
        supervision); a physical link's KKLs run under the supervisor's gain tracker."""
        return not self.physical

    @property
    def nominal_filters(self) -> bool:
        """Whether ``--filter-distance nominal`` applies: the bench's noise rescaled to
        its nominal distance (a physical link's noise depends on the signal)."""
        return not self.physical

    @property
    def has_receiver_hardware(self) -> bool:
        """Whether the link has a detector and optics that disturbances of the receiver
        (sunlight, a saturating front end) act on."""
        return self.physical

    def lensed(self, field: float) -> LinkPreset:
        """This preset with a lens in front of its detector that narrows the half-power
        field to ``field`` [rad]: the same detector's étendue, so the lens's aperture
        gathers (sin(field of view) / sin(field))^2 times the bare detector's light
        (about 8 for 30 to 10 deg), and the background light stays as it was."""
        o = self.optics
        if o is None:
            raise LedsimError(f"link {self.name!r} is the paper's bench: it has no lens")
        gain = (math.sin(o.field_of_view) / math.sin(field)) ** 2
        return replace(self, optics=replace(
            o, field_of_view=field, collection_area=o.collection_area * gain,
            source=f"{o.source}; a lens to a {math.degrees(field):g} deg half-power field, "
                   "the detector's étendue kept"))

    def link(self, water: Water, depth: float = 10.0, surface_irradiance: float = 0.0
             ) -> RadiometricLink:
        """The physical link in ``water``."""
        if not self.physical:
            raise LedsimError(f"link {self.name!r} is the paper's bench, not a physical link")
        return RadiometricLink(self.name, self.transmitter, DETECTORS[self.detector],
                               self.optics, water, depth, surface_irradiance)


_AQUA = ("Doniec, Vasilescu, Chitre, Detweiler, Hoffmann-Kuhnt and Rus, 'AquaOptical: a "
         "lightweight device for high-rate long-range underwater point-to-point "
         "communication', OCEANS 2009 (MIT 1721.1/59310)")
_LUMA = "Hydromea LUMA product figures (over 50 m at 500 kbit/s, 2-5 W optical)"
_BLUECOMM = ("Sonardyne BlueComm 200 (450 nm LEDs): 12.5 Mbit/s video to 88 m in a 2015 "
             "sea trial")

#: The presets of ``--link``.
LINK_PRESETS = {p.name: p for p in (
    LinkPreset("paper", "the paper's bench: 8.5 cm, about 1 W on a photodiode, a fixed "
               "noise of 32 mW (docs/model.md)", bit_rate=1e3),
    LinkPreset(
        "aquaoptical",
        "AquaOptical long-range modem (MIT, 2009): blue LEDs to a Si photodiode",
        Transmitter(1.66, 470.0, math.radians(20.0),
                    "LED power set on the 30 m clear-water figure (scripts/link_presets.py "
                    "--calibrate); 470 nm and a 20 deg beam assumed (royal-blue LEDs with "
                    "reflectors)"),
        "si-pin",
        ReceiverOptics(1e-4, math.radians(30.0), 0.9, 40.0,
                       "bare 1 cm^2 photodiode behind a flat window; 30 deg half-power "
                       "field assumed"),
        distance=20.0, bit_rate=1.2e6, water="clear-ocean",
        published=(PublishedFigure(30.0, 1.2e6, "clear-ocean", "set", _AQUA),
                   PublishedFigure(9.0, 0.6e6, "visibility 3 m", "predict", _AQUA))),
    LinkPreset(
        "luma",
        "Hydromea LUMA class modem: 450 nm LEDs, a wide beam, a Si APD",
        Transmitter(3.5, 450.0, math.radians(30.0),
                    "3.5 W: the middle of the published 2-5 W; 30 deg beam assumed"),
        "si-apd",
        ReceiverOptics(math.pi * 0.005**2, math.radians(30.0), 0.9, 40.0,
                       "bare APD behind a flat window (no lens is published); 30 deg "
                       "half-power field assumed"),
        distance=30.0, bit_rate=5e5, water="clear-ocean",
        published=(PublishedFigure(50.0, 5e5, "clear-ocean", "check", _LUMA),)),
    LinkPreset(
        "bluecomm-200",
        "Sonardyne BlueComm 200 class modem: 450 nm LED array to a photomultiplier",
        Transmitter(10.0, 450.0, math.radians(30.0),
                    "10 W optical and a 30 deg beam assumed (a multi-LED array)"),
        "pmt",
        ReceiverOptics(math.pi * 0.004**2, math.radians(30.0), 0.8, 20.0,
                       "PMT window, 30 deg half-power field assumed"),
        distance=50.0, bit_rate=12.5e6, water="clear-ocean",
        published=(PublishedFigure(88.0, 12.5e6, "clear-ocean", "check", _BLUECOMM),)),
)}


#: The link ``ledsim run``, ``demo`` and the other commands use without ``--link``: a
#: real modem at a realistic range (``--link paper`` is the paper's bench; the Python
#: API's ``RunConfig`` keeps the bench).
DEFAULT_LINK = "luma"


def preset_named(name: str) -> LinkPreset:
    """The link preset ``name``; a one-line error naming the allowed ones otherwise."""
    return named(LINK_PRESETS, name, "link")


def default_distance(name: str) -> float:
    """Preset ``name``'s default distance [m] (an unknown name: the bench's; a run's
    validation then names it)."""
    preset = LINK_PRESETS.get(name)
    return PAPER_DISTANCE if preset is None else preset.distance


def water_of(preset: LinkPreset, water: str | None = None,
             attenuation: float | None = None) -> Water:
    """The run's water: ``water`` (a type, default the preset's), at beam attenuation
    ``attenuation`` [1/m] when one is set."""
    w = water_named(preset.water if water is None else water)
    if attenuation is None:
        return w
    return w.with_attenuation(attenuation, preset.transmitter.wavelength
                              if preset.physical else None)


def link_constants(name: str = "paper", distance: float | None = None,
                   water: str | None = None, attenuation: float | None = None,
                   base: LinkConstants | None = None,
                   lens_field: float | None = None) -> LinkConstants:
    """The constants of link ``name`` at ``distance`` [m] (default the preset's) in
    ``water`` and ``attenuation``, and with a lens of half-power field ``lens_field``
    [rad] (:meth:`LinkPreset.lensed`; None: the bare detector). The paper's bench with
    neither is exactly ``LinkConstants(distance=...)``; with them its b is the water's c
    (Beer-Lambert, the paper's form)."""
    preset = preset_named(name)
    if lens_field is not None:
        preset = preset.lensed(lens_field)
    d = preset.distance if distance is None else distance
    base = LinkConstants() if base is None else base
    if not preset.physical:
        c = base.with_(distance=d)
        if water is None and attenuation is None:
            return c
        return c.with_(attenuation=water_of(preset, water, attenuation).attenuation)
    return preset.link(water_of(preset, water, attenuation)).constants(d, base)


#: The relative noise [-] of the physical KKLs' reference world: the pointing samples'
#: noise over the signal on a physical link near half its range at the FEC limit (the
#: analog noise, which dithers the ADC's averaged conversions: 4e-5 to 1e-4 at luma's
#: half range in the three waters, 1e-3 near the range). The bank's members are learned
#: for 1-13 times it and the scheduled KKL for 1-16 times it
#: (``observer.kkl.scheduled.ScheduledDesign.noise_range``).
KKL_REFERENCE_NOISE = 5e-5


def kkl_reference_constants(base: LinkConstants | None = None) -> LinkConstants:
    """The world the physical presets' KKL is trained in and runs against: the paper's
    bench geometry (d = 0.085 m, about 1 W on a photodiode) with the physical receiver's
    response g(phi) (every physical preset's: a 30 deg Gaussian) and its relative noise
    :data:`KKL_REFERENCE_NOISE`, constant. The supervisor's gain tracker maps a run's
    powers onto it, as it maps the bench's other distances onto 0.085 m."""
    from ledsim.radiometry.optics import peak_power

    base = LinkConstants() if base is None else base
    response = next(p for p in LINK_PRESETS.values() if p.physical).link(
        WATER_TYPES["clear-ocean"]).response
    c = base.with_(distance=PAPER_DISTANCE, receiver=response)
    return c.with_(measurement_noise_var=(KKL_REFERENCE_NOISE * peak_power(c)) ** 2)


__all__ = ["DEFAULT_LINK", "KKL_REFERENCE_NOISE", "LINK_PRESETS", "WATER_TYPES", "LinkPreset",
           "PublishedFigure", "default_distance", "kkl_reference_constants", "link_constants",
           "preset_named", "water_of"]
