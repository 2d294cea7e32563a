"""One typed source of truth for the link's physical constants.

The paper (Li et al., "Data-Driven State Estimation for LED Underwater Optical
Communication") gives the model's form but not most of its constants; the values
chosen here and the reasoning behind each are written out in ``docs/model.md``.
Everything that computes a power, a transition or a noise sample reads them from a
:class:`LinkConstants` instance, and checkpoints record them so a mismatch is caught.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING, Protocol

from ledsim.errors import LedsimError, check_ranges

if TYPE_CHECKING:  # imported where used: the CLI starts before numpy (thread pinning)
    from ledsim.physics.layout import ReceiverLayout
    from observer.noise import MeasurementNoise

#: The paper's link distance d0 [m]: the default everywhere, and the distance of the
#: shipped MuJoCo bank that serves every other.
PAPER_DISTANCE = 0.085

#: The closest the receiver can come to the LED in the MuJoCo scene [m]: their housings
#: touch (the LED's 6 mm dome against the photodiodes' lenses, in ``led_link.xml``).
#: Closer, the scene's geometry has no meaning (and at 1e-183 m its rays divided by
#: zero); the radiometry alone (``ledsim budget``'s search for its range) goes closer.
MIN_DISTANCE = 0.01

#: The quietest measurement noise a run may ask for, over the nominal (``--noise-scale``)
#: [-]: a thousandth of the datasheet's. Quieter has no receiver behind it (and at 5e-324
#: the link's peak SNR divided by zero).
MIN_NOISE_SCALE = 1e-3

#: The slowest data a link may carry (``--bit-rate``) [bit/s]: a bit a second. Slower
#: has no modem behind it (and at 5e-324 bit/s the budget's SNR was infinite).
MIN_BIT_RATE = 1.0

#: Standard gravity [m/s^2]: the scene's (``led_link.xml``'s default), what an
#: accelerometer at rest reads, the waves' dispersion and the datasheets' g.
GRAVITY = 9.81


class ConfigError(LedsimError):
    """A user-supplied constant is out of its allowed range."""


class PhysicalLink(Protocol):
    """What the constants need of a physical link
    (:class:`ledsim.radiometry.link.RadiometricLink`): its receiver's noise."""

    name: str

    def noise(self, bandwidth: float, n_output: int = 2, scale: float = 1.0,
              digitised: bool = True) -> MeasurementNoise: ...


@dataclass(frozen=True)
class ReceiverResponse:
    """Two-Gaussian angular response g(phi) of a photodiode, paper eq. (modified-gaussian2).

    ``g(phi) = a1 exp(-((phi-b1)/c1)^2) + a2 exp(-((phi+b2)/c2)^2)``, dimensionless,
    phi in rad. Main lobe slightly off-axis (lens/mount misalignment b1) plus a side
    shoulder at -b2: non-monotonic on the training domain, as in N'Doye et al. (2020).
    """

    a1: float = 1.0  # main-lobe gain [-]
    b1: float = 0.05  # main-lobe offset [rad]
    c1: float = 0.30  # main-lobe width [rad] (FWHM = 2 sqrt(ln 2) c1 = 0.50 rad = 29 deg)
    a2: float = 0.30  # shoulder gain [-]
    b2: float = 0.25  # shoulder offset, towards negative phi [rad]
    c2: float = 0.20  # shoulder width [rad]


@dataclass(frozen=True)
class LinkConstants:
    """Constants of the LED link and of the receiver dynamics (SI units).

    Attributes:
        Te: control / sampling period [s].
        dphi: angular offset between the two photodiode normals, Delta phi [rad].
        distance: link distance d between LED and receiver [m] (paper's d0 = 0.085 m).
        power_scale: a in eq. (pow-d-theta-phi): LED radiant intensity x detector
            area x responsivity [W m^2]; gives about 1 W at 8.5 cm on axis.
        attenuation: b (= c in eq. eq-3a), beam attenuation of the water [1/m]
            (clear ocean, Mobley 1994).
        led_half_angle: LED half-power semi-angle [rad]; sets the Lambertian order of
            I(theta) = cos(theta)^m.
        theta: emission angle of the line of sight w.r.t. the LED axis [rad] (paper: fixed).
        measurement_noise_var: variance of the additive power noise [W^2] (paper: 0.001).
        process_noise_std: per-step standard deviation of (w1 [rad], w2 [rad/s]).
        receiver: the photodiode response g(phi).
        link: the physical link these constants were built from
            (:meth:`ledsim.radiometry.link.RadiometricLink.constants`), whose receiver
            noise depends on the signal; None: the paper's bench, whose noise does not.
        receiver_layout: the receiver's photodiodes and gimbal axes
            (:class:`~ledsim.physics.layout.ReceiverLayout`); None: the paper's pair,
            ``dphi`` apart, on one axis.
    """

    Te: float = 0.01
    dphi: float = math.radians(6.0)
    distance: float = PAPER_DISTANCE
    power_scale: float = 7.3e-3
    attenuation: float = 0.15
    led_half_angle: float = math.radians(20.0)
    theta: float = 0.0
    measurement_noise_var: float = 1e-3
    process_noise_std: tuple[float, float] = (1e-4, 2e-4)
    receiver: ReceiverResponse = field(default_factory=ReceiverResponse)
    link: PhysicalLink | None = None
    receiver_layout: ReceiverLayout | None = None

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise :class:`ConfigError` naming the first out-of-range constant."""
        checks = [
            ("Te", self.Te, self.Te > 0, "> 0 s"),
            ("distance", self.distance, self.distance > 0, "> 0 m"),
            ("dphi", self.dphi, self.dphi != 0 and abs(self.dphi) < math.pi / 2,
             "non-zero and |dphi| < pi/2 rad"),
            ("power_scale", self.power_scale, self.power_scale > 0, "> 0 W m^2"),
            ("attenuation", self.attenuation, self.attenuation >= 0, ">= 0 1/m"),
            ("led_half_angle", self.led_half_angle, 0 < self.led_half_angle < math.pi / 2,
             "in (0, pi/2) rad"),
            ("measurement_noise_var", self.measurement_noise_var,
             self.measurement_noise_var >= 0, ">= 0 W^2"),
            ("receiver.c1", self.receiver.c1, self.receiver.c1 > 0, "> 0 rad"),
            ("receiver.c2", self.receiver.c2, self.receiver.c2 > 0, "> 0 rad"),
        ]
        check_ranges(checks, ConfigError, "=")
        if len(self.process_noise_std) != 2 or min(self.process_noise_std) < 0:
            raise ConfigError(
                f"process_noise_std={self.process_noise_std!r} is not allowed: "
                "must be two values >= 0")

    @property
    def lambertian_order(self) -> float:
        """m such that cos(led_half_angle)^m = 1/2."""
        return -math.log(2.0) / math.log(math.cos(self.led_half_angle))

    @property
    def measurement_noise_std(self) -> float:
        """Standard deviation of the power noise [W]."""
        return math.sqrt(self.measurement_noise_var)

    @functools.cached_property  # read on every model call: once per instance
    def layout(self) -> ReceiverLayout:
        """The receiver: ``receiver_layout``, or the paper's pair of photodiodes, Delta phi
        apart, on one axis."""
        if self.receiver_layout is not None:
            return self.receiver_layout
        from ledsim.physics.layout import paper_layout

        return paper_layout(self.dphi)

    def measurement_noise(self, scale: float = 1.0) -> MeasurementNoise:
        """The photodiodes' power noise at noise scale ``scale`` [-]: the one object
        the sensor, the estimators, the supervisor, the env and the link budget read:
        the physical link's over the pointing channel's bandwidth 1 / (2 Te), or the
        paper's."""
        if self.link is not None:
            return self.link.noise(1.0 / (2.0 * self.Te), self.layout.n_photodiodes, scale)
        from observer.noise import MeasurementNoise

        return MeasurementNoise(self.measurement_noise_std, self.layout.n_photodiodes, scale)

    def with_(self, **changes) -> LinkConstants:
        """A validated copy with some constants changed."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        """The constants as JSON-ready data (``link`` only for a physical link, so the
        paper's metadata keeps its keys)."""
        d = asdict(self)
        d["process_noise_std"] = list(self.process_noise_std)
        if self.link is None:
            del d["link"]
        if self.receiver_layout is None:  # the paper's, from dphi: the metadata keeps its keys
            del d["receiver_layout"]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> LinkConstants:
        d = dict(d)
        d["receiver"] = ReceiverResponse(**d.get("receiver", {}))
        d["process_noise_std"] = tuple(d.get("process_noise_std", (1e-4, 2e-4)))
        if d.get("receiver_layout") is not None:
            from ledsim.physics.layout import ReceiverLayout

            d["receiver_layout"] = ReceiverLayout.from_dict(d["receiver_layout"])
        if d.get("link") is not None:
            raise ConfigError("these constants are of a physical link: read them with "
                              "ledsim.radiometry.link.constants_from_dict")
        return cls(**d)


@dataclass(frozen=True)
class NavigationNoise:
    """Noise of the vehicle's own sensors (SI units), with where each figure comes from.

    White noise is given as a density and sampled once per control step Te, over the
    bandwidth 1 / (2 Te): standard deviation = density x sqrt(1 / (2 Te)). A bias drifts
    as a first-order Gauss-Markov process whose stationary spread is the datasheet's
    in-run bias instability (the usual model of that figure), and starts at a draw from
    that spread (what is left after the vehicle's own calibration).

    Attributes:
        gyro_noise_density: [rad/s/sqrt(Hz)]; 0.007 deg/s/sqrt(Hz), Xsens MTi-1 series
            datasheet (a small industrial MEMS IMU).
        gyro_bias_instability: [rad/s]; 10 deg/h, same datasheet.
        gyro_bias_time: correlation time of the gyro bias's drift [s].
        accel_noise_density: [m/s^2/sqrt(Hz)]; 120 ug/sqrt(Hz), same datasheet.
        accel_bias_instability: [m/s^2]; 0.03 mg, same datasheet.
        accel_bias_time: correlation time of the accelerometer bias's drift [s].
        dvl_noise: standard deviation of one DVL velocity measurement, each axis [m/s]:
            a few mm/s, the single-ping noise manufacturers of 1 MHz bottom-tracking DVLs
            quote at these low speeds (e.g. Nortek DVL1000); its long-term bias (about
            0.1 %) is left out.
        dvl_rate: DVL pings per second [Hz] (8 Hz: the DVL1000's highest rate); the last
            velocity is held between pings.
        encoder_bits: resolution of the gimbal's absolute encoder [bits]: 14, a magnetic
            encoder such as ams AS5047P (a step of 2 pi / 2^14 = 3.8e-4 rad).
        fix_noise: standard deviation of an acoustic position fix, each axis [m]: a short
            baseline or USBL fix at a few metres (about 1 % of the range).
        fix_rate: acoustic fixes per second [Hz].
        depth_noise: standard deviation of the pressure sensor's depth [m]: 2 mm, the
            0.2 mbar resolution of a Blue Robotics Bar30 (TE MS5837-30BA), read every
            control step.
        magnetometer_noise: standard deviation of one magnetometer reading, each axis
            [T]: 0.6 uT, the RMS noise of a Bosch BMM150 in its regular preset (the
            heading reference; against the scene's 25 uT horizontal field, 1.4 deg a
            reading).
        magnetometer_rate: magnetometer readings per second [Hz]: 10 Hz, the BMM150's
            output rate in that preset.
        fix_latency: time from an acoustic fix's measurement to its arrival [s]: the
            fix is of where the vehicle was then (a USBL's travel time and processing:
            0.1-1 s at tens of metres). Allowed 0-5 s.
        fix_range_error: a fix's error that grows with the slant range to the USBL
            transceiver (the scene's ``usbl`` site), as a share of it [-]: the error's
            standard deviation is ``hypot(fix_noise, fix_range_error * range)`` (USBL
            systems quote 0.1-1 % of the slant range). Allowed 0-0.1.
        fix_outlier_share: share of fixes that are outliers (multipath, a wrong
            detection) [-]. Allowed 0-0.5.
        fix_outlier_size: standard deviation of an outlier's extra error, each axis [m].
            Allowed 0-100 m.
    """

    gyro_noise_density: float = math.radians(0.007)
    gyro_bias_instability: float = math.radians(10.0) / 3600.0
    gyro_bias_time: float = 100.0
    accel_noise_density: float = 120e-6 * GRAVITY
    accel_bias_instability: float = 0.03e-3 * GRAVITY
    accel_bias_time: float = 100.0
    dvl_noise: float = 0.004
    dvl_rate: float = 8.0
    encoder_bits: int = 14
    fix_noise: float = 0.03
    fix_rate: float = 1.0
    depth_noise: float = 0.002
    magnetometer_noise: float = 0.6e-6
    magnetometer_rate: float = 10.0
    fix_latency: float = 0.0
    fix_range_error: float = 0.0
    fix_outlier_share: float = 0.0
    fix_outlier_size: float = 1.0

    def __post_init__(self) -> None:
        v = self.__dict__
        check_ranges([(n, v[n], v[n] >= 0, ">= 0 and finite") for n in (
            "gyro_noise_density", "gyro_bias_instability", "accel_noise_density",
            "accel_bias_instability", "dvl_noise", "fix_noise", "depth_noise",
            "magnetometer_noise")], ConfigError, "=")
        check_ranges([(n, v[n], v[n] > 0, "> 0 and finite") for n in (
            "gyro_bias_time", "accel_bias_time", "dvl_rate", "fix_rate",
            "magnetometer_rate")], ConfigError, "=")
        check_ranges([(n, v[n], 0 <= v[n] <= high, f"in [0, {high:g}]{unit}")
                      for n, high, unit in (("fix_latency", 5.0, " s"),
                                            ("fix_range_error", 0.1, ""),
                                            ("fix_outlier_share", 0.5, ""),
                                            ("fix_outlier_size", 100.0, " m"))],
                     ConfigError, "=")
        if not (isinstance(self.encoder_bits, int) and 1 <= self.encoder_bits <= 32):
            raise ConfigError(f"encoder_bits={self.encoder_bits!r} is not allowed: must be an "
                              "integer in 1..32")

    @property
    def encoder_step(self) -> float:
        """Quantisation step of the encoder [rad]."""
        return 2.0 * math.pi / 2**self.encoder_bits

