"""The world part of a run's spec: the MuJoCo world an experiment runs in (the link,
the water, the depths, the receiver's head, the scene)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ledsim.agent.autopilot import StationKeeping
from ledsim.constants import NavigationNoise
from ledsim.loop.registry import head_of
from ledsim.loop.validation import keeping_gains, navigation_noise
from ledsim.physics.layout import quad_layout
from ledsim.physics.scene import DEFAULT_DEPTH, WorldConfig
from ledsim.radiometry.link_presets import default_distance, link_constants


@dataclass(frozen=True)
class WorldPart:
    """The MuJoCo world of an experiment.

    Attributes:
        distance: link distance d [m] (None: the link preset's, 0.085 m on the paper's
            bench).
        torque_limit: gimbal motor torque limit [N m].
        noise_scale: multiplies the measurement-noise standard deviation [-].
        scene: MJCF scene file (None: the shipped one).
        integrator: MuJoCo integrator of the world (``implicitfast``, ``euler``, ...).
        station_keeping: the vehicle holds its pose on its thrusters, from its own
            navigation (:class:`~ledsim.agent.autopilot.Vehicle`); off: it drifts.
        imu_noise: ``key=value`` settings of the vehicle's sensors' noise
            (:class:`~ledsim.constants.NavigationNoise`'s fields; the rest keep their
            datasheet figures).
        station_keeping_gains: ``key=value`` settings of the station keeping's gains
            (:class:`~ledsim.agent.autopilot.StationKeeping`'s fields).
        link: the link preset (:data:`ledsim.radiometry.link_presets.LINK_PRESETS`):
            ``paper``, the paper's bench, or a real LED modem.
        water: the water type (None: the preset's); ``attenuation``: its beam
            attenuation c instead [1/m] (None: the type's).
        bit_rate: the data's bit rate [bit/s] (None: the preset's).
        depth: the receiver vehicle's depth below the still surface [m] (the waves'
            decay, the daylight of ``flicker``, the surface in the video).
        transmitter_depth: the LED's depth [m] (None: the receiver's).
        receiver_dome: the receiver's head turns inside a dome, out of the water's flow
            (``--receiver-dome``).
        sea_depth: the sea's depth [m], where the seabed stands (None: below both ends).
        gimbal: the receiver's gimbal, ``yaw`` (the paper's one axis) or ``pan-tilt``
            (azimuth and elevation) (None: the receiver's, or the link's: ``yaw`` on the
            paper's bench, ``pan-tilt`` on a physical link, but ``yaw`` where the run
            asks for what only it runs: :func:`~ledsim.loop.registry.yaw_only`).
        receiver: its photodiodes, ``pair`` (the paper's) or ``quad`` (a data detector
            on the boresight and four pointing photodiodes ``dphi`` off it in azimuth
            and elevation) (None: the gimbal's).
        channel_mismatch: on the quad, the gain mismatch between opposite pointing
            photodiodes [-]: each pair's first reads 1 + m/2 of its light, its second
            1 - m/2 (a head's channels differ); the estimators are told it, as the
            head's calibration measured it (0: matched channels).
        transmitter_aimed: the LED's axis points at the receiver (a node that faces the
            vehicle above or below it); off: level, whatever the depths.
        mission: a JSON or TOML file of waypoints the receiver's vehicle flies, then
            keeps station at the last (:mod:`ledsim.agent.guidance`; None: it keeps
            station where it starts).
        node_error: on the move, how far off the vehicle's navigation believes the node
            is [m] (a standard deviation per axis, drawn from the run's seed; 0: its
            position is known). The vehicle then learns it from where its head finds the
            LED (:class:`~ledsim.agent.node_cue.NodeCue`).
        lens_field_deg: a lens in front of the physical receiver's detector, narrowing
            its half-power field to this many degrees and gathering a larger aperture's
            light (the detector's étendue kept: about 8x for 30 to 10 deg) (None: the
            bare detector).
    """

    distance: float | None = None
    torque_limit: float = 0.05
    noise_scale: float = 1.0
    scene: str | None = None
    integrator: str = "implicitfast"
    station_keeping: bool = True
    imu_noise: tuple[str, ...] = ()
    station_keeping_gains: tuple[str, ...] = ()
    link: str = "paper"
    water: str | None = None
    attenuation: float | None = None
    bit_rate: float | None = None
    depth: float = DEFAULT_DEPTH
    transmitter_depth: float | None = None
    receiver_dome: bool = False
    sea_depth: float | None = None
    gimbal: str | None = None
    receiver: str | None = None
    channel_mismatch: float = 0.0
    transmitter_aimed: bool = False
    lens_field_deg: float | None = None
    mission: str | None = None
    node_error: float = 0.0

    def __post_init__(self) -> None:
        if self.distance is None:  # the link preset's (0.085 m on the paper's bench)
            object.__setattr__(self, "distance", default_distance(self.link))

    def navigation_noise(self) -> NavigationNoise:
        """The vehicle's sensors' noise: the defaults with ``imu_noise`` applied."""
        return navigation_noise(self.imu_noise)

    def keeping_gains(self) -> StationKeeping:
        """The station keeping's gains: the defaults with ``station_keeping_gains``."""
        return keeping_gains(self.station_keeping_gains)

    @property
    def lens_field(self) -> float | None:
        """The lens's half-power field [rad] (None: no lens)."""
        return None if self.lens_field_deg is None else math.radians(self.lens_field_deg)

    @property
    def head(self) -> tuple[str, str]:
        """(gimbal, receiver) as run (:func:`~ledsim.loop.registry.head_of`)."""
        return head_of(self.gimbal, self.receiver, self.link)

    @property
    def two_axes(self) -> bool:
        """The run points a pan-tilt head with a quad."""
        return self.head == ("pan-tilt", "quad")

    def channel_gains(self):
        """Each photodiode's gain over its nominal [-] (None: all 1): on the quad, the
        data detector 1 and each pointing pair 1 +- ``channel_mismatch`` / 2."""
        if not self.channel_mismatch:
            return None
        half = 0.5 * self.channel_mismatch
        return (1.0, 1.0 + half, 1.0 - half, 1.0 + half, 1.0 - half)

    def world_config(self, distance: float | None = None,
                     led: tuple[float, float] | None = None) -> WorldConfig:
        """The MuJoCo world (at ``distance`` [m] instead, when given; ``led``: the LED's
        axis turned by (yaw, pitch) [rad], a mission scenario's node); its control
        period Te is the link constants' (5 physics steps of 2 ms)."""
        extra = {} if self.scene is None else {"xml": self.scene}
        d = self.distance if distance is None else distance
        constants = link_constants(self.link, d, self.water, self.attenuation,
                                   lens_field=self.lens_field)
        if self.two_axes:
            constants = replace(constants, receiver_layout=quad_layout(constants.dphi))
        if self.transmitter_aimed:
            extra["led_pitch"] = aimed_pitch(self.depth, self.transmitter_depth, d)
        if led is not None:
            extra["led_yaw"], extra["led_pitch"] = led
        return WorldConfig(constants=constants,
                           torque_limit=self.torque_limit, integrator=self.integrator,
                           depth=self.depth, transmitter_depth=self.transmitter_depth,
                           receiver_dome=self.receiver_dome, sea_depth=self.sea_depth,
                           **extra)


def aimed_pitch(depth: float, transmitter_depth: float | None, distance: float) -> float:
    """How far up [rad] an LED ``transmitter_depth`` m deep aims its axis at a receiver
    ``depth`` m deep, ``distance`` m away (slant) (0 when level)."""
    if transmitter_depth is None:
        return 0.0
    return math.asin(max(-1.0, min(1.0, (transmitter_depth - depth) / distance)))
