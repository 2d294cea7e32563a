"""The scene: every knob of the MuJoCo world, applied to the MJCF through ``mujoco.MjSpec``.

The MJCF file ``led_link.xml`` sits beside this module (package data). :func:`build_spec`
loads it, checks the names the code relies on, and applies a :class:`WorldConfig`
(link distance, photodiode offset, LED pose, hull mass, water, torque limit): no XML
templating.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from ledsim.constants import MIN_DISTANCE, ConfigError, LinkConstants
from ledsim.errors import LedsimError, check_ranges
from ledsim.files.resources import scene_path
from ledsim.physics.head import build_head, receiver_centre
from ledsim.physics.sea_scene import apply_sea, place_seabed, seabed_check

#: Former module-level name of the default scene.
SCENE = scene_path()


#: The receiver vehicle's depth below the still surface when a run sets none [m].
DEFAULT_DEPTH = 10.0


class WorldError(LedsimError):
    """The scene cannot be built as asked (bad file, name, or geometry)."""


#: MuJoCo integrators by their MJCF names.
INTEGRATORS = {"implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
               "euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
               "rk4": mujoco.mjtIntegrator.mjINT_RK4}


@dataclass(frozen=True)
class WorldConfig:
    """Every knob of the MuJoCo world (SI units).

    Attributes:
        constants: optics and dynamics constants shared with the observer's model;
            ``constants.distance`` is the LED-receiver distance and ``constants.dphi``
            the angle between the photodiode normals.
        xml: scene file.
        led_lateral_offset: LED displacement across the link (world y) [m].
        led_yaw: rotation of the LED axis about world z away from the receiver [rad];
            sets the emission angle theta.
        led_pitch: rotation of the LED axis up from level [rad] (after ``led_yaw``): a
            node on the seabed that faces a vehicle above it.
        hull_mass: AUV hull mass [kg]; None = neutrally buoyant (mass of displaced water).
        water_density: fluid density [kg/m^3] (0: in air, no fluid forces).
        water_viscosity: dynamic viscosity [Pa s].
        torque_limit: gimbal motor torque limit [N m].
        gimbal_damping: hinge bearing damping [N m s/rad].
        timestep: physics step [s]; ``constants.Te`` must be a multiple of it.
        n_rays: rays per photodiode over the LED aperture (1 = centre only).
        aperture_radius: radius of the LED's emitting aperture [m].
        integrator: MuJoCo integrator, one of :data:`INTEGRATORS` (implicitfast treats
            the fluid damping implicitly; euler is cheaper per step, see docs/physics.md).
        metacentric_height: the hull's centre of buoyancy above its centre of mass [m]
            (BG): buoyancy's righting moment in pitch and roll. 2 cm, the order of a
            small torpedo AUV's (a REMUS-100's is about 1-2 cm).
        depth: the receiver vehicle's depth below the still surface [m] (the waves'
            decay, the daylight, the surface in the video); the hull starts at world
            z = 0, so the surface is at z = ``depth``.
        transmitter_depth: the LED's depth [m] (None: the receiver's). A different depth
            puts the LED above or below the receiver's plane: an elevation the one-axis
            gimbal cannot turn to.
        receiver_dome: the receiver's head turns inside a dome (a window over the
            gimbal): the water's flow puts no torque on it. False: the head is open to
            the water, as on the paper's bench (docs/sea.md measures both).
        sea_depth: the sea's depth under the still surface [m]: the seabed stands
            there, at least :data:`~ledsim.physics.sea_scene.SEABED_CLEARANCE` below
            both ends (None: the scene's seabed, 2.5 m under the receiver, and as far
            under the LED where the LED is deeper).
    """

    constants: LinkConstants = field(default_factory=LinkConstants)
    xml: Path = field(default_factory=scene_path)
    led_lateral_offset: float = 0.0
    led_yaw: float = 0.0
    led_pitch: float = 0.0
    hull_mass: float | None = None
    water_density: float = 1000.0
    water_viscosity: float = 0.00089
    torque_limit: float = 0.05
    gimbal_damping: float = 1e-4
    timestep: float = 0.002
    n_rays: int = 5
    aperture_radius: float = 0.003
    integrator: str = "implicitfast"
    metacentric_height: float = 0.02
    depth: float = DEFAULT_DEPTH
    transmitter_depth: float | None = None
    receiver_dome: bool = False
    sea_depth: float | None = None

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ConfigError(f"integrator={self.integrator!r} is not allowed: choose one "
                              f"of {', '.join(INTEGRATORS)}")
        checks = [
            ("torque_limit", self.torque_limit, self.torque_limit > 0, "> 0 N m"),
            ("water_density", self.water_density, self.water_density >= 0, ">= 0 kg/m^3"),
            ("water_viscosity", self.water_viscosity, self.water_viscosity >= 0, ">= 0 Pa s"),
            ("gimbal_damping", self.gimbal_damping, self.gimbal_damping >= 0, ">= 0 N m s/rad"),
            ("timestep", self.timestep, 0 < self.timestep <= self.constants.Te,
             f"in (0, Te={self.constants.Te}] s"),
            ("n_rays", self.n_rays, self.n_rays >= 1, ">= 1"),
            ("aperture_radius", self.aperture_radius, self.aperture_radius >= 0, ">= 0 m"),
            ("metacentric_height", self.metacentric_height, self.metacentric_height >= 0,
             ">= 0 m"),
            ("depth", self.depth, 1.0 <= self.depth <= 500.0, "in [1, 500] m"),
            ("constants.distance", self.constants.distance,
             self.constants.distance >= MIN_DISTANCE,
             f">= {MIN_DISTANCE:g} m (closer, the LED's and the receiver's housings touch)"),
        ]
        if self.transmitter_depth is not None:
            checks.append(("transmitter_depth", self.transmitter_depth,
                           0.2 <= self.transmitter_depth <= 500.0, "in [0.2, 500] m"))
        if self.hull_mass is not None:
            checks.append(("hull_mass", self.hull_mass, self.hull_mass > 0, "> 0 kg"))
        if self.sea_depth is not None:
            checks.append(seabed_check(self.sea_depth, self.depth, self.transmitter_depth))
        check_ranges(checks, ConfigError, "=")
        ratio = self.constants.Te / self.timestep
        if abs(ratio - round(ratio)) > 1e-9:
            raise ConfigError(f"timestep={self.timestep!r} is not allowed: Te="
                              f"{self.constants.Te} must be a whole multiple of it")

    @property
    def substeps(self) -> int:
        return round(self.constants.Te / self.timestep)


def _set_yaw(element, angle: float, pitch: float = 0.0) -> None:
    """Turn the LED's body by ``angle`` about world z, then its axis (the body's -x)
    up by ``pitch`` [rad] (about its y)."""
    element.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    if pitch == 0.0:
        element.quat = [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]
        return
    cy, sy = math.cos(angle / 2), math.sin(angle / 2)
    # -x turned up by pitch is a turn of pitch about y: q_z(angle) q_y(pitch)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    element.quat = [cy * cp, -sy * sp, cy * sp, sy * cp]


def transmitter_rise(depth: float, transmitter_depth: float | None, distance: float,
                     names: tuple[str, str] = ("depth", "transmitter_depth")) -> float:
    """How far the LED stands above the receiver [m] (``transmitter_depth`` None: level),
    refusing depths that differ by the link ``distance`` or more (``names``: what the
    message calls the two depths)."""
    if transmitter_depth is None:
        return 0.0
    if abs(depth - transmitter_depth) >= distance:
        raise WorldError(f"{names[1]} {transmitter_depth:g} m is not allowed with "
                         f"{names[0]} {depth:g} m: the depths must differ by less than the "
                         f"link distance {distance:g} m")
    return depth - transmitter_depth


def build_spec(config: WorldConfig) -> mujoco.MjSpec:
    """Load the scene and apply ``config`` through MjSpec (no XML templating)."""
    path = Path(config.xml)
    if not path.exists():
        raise WorldError(f"scene file {str(path)!r} does not exist")
    if not path.is_file():
        raise WorldError(f"scene file {str(path)!r} is not a regular file")
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as exc:  # mujoco raises ValueError with the parser message
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise WorldError(f"scene file {str(path)!r} is not valid MJCF: {first}") from None
    c = config.constants
    layout = c.layout.buildable()
    first = layout.axes[0]
    for kind, name in [("body", "auv"), ("body", "gimbal"), ("body", "transmitter"),
                       ("body", "occluder"), ("site", "led"), ("joint", first.joint),
                       ("actuator", first.motor), ("geom", "hull")]:
        if getattr(spec, kind)(name) is None:
            raise WorldError(f"scene file {str(path)!r} has no {kind} named {name!r}")
    spec.option.timestep = config.timestep
    spec.option.integrator = INTEGRATORS[config.integrator]
    spec.option.density = config.water_density
    spec.option.viscosity = config.water_viscosity

    # Each photodiode's normal turned to its offsets, so that its incidence angle is
    # phi + offset (paper eq. eq-4a: offsets 0 and dphi); axes the scene lacks, built.
    sites = build_head(spec, layout, config.gimbal_damping, WorldError)

    # LED at distance d in front of the receiver centre (midpoint of the photodiodes).
    gimbal = spec.body("gimbal")
    centre = np.asarray(gimbal.pos) + receiver_centre(sites)
    tx = spec.body("transmitter")
    # the LED's depth lifts it out of the receiver's plane; d stays the slant distance
    rise = transmitter_rise(config.depth, config.transmitter_depth, c.distance)
    ahead = math.sqrt(c.distance**2 - rise**2)
    tx.pos = [centre[0] + ahead, centre[1] + config.led_lateral_offset, centre[2] + rise]
    if config.receiver_dome:  # the head turns in still water behind a window
        shelter(spec, [spec.body("gimbal")] + [spec.body(a.name) for a in layout.axes[1:]])
    place_seabed(spec, config.sea_depth, config.depth, rise, WorldError)
    if c.link is not None:  # metres of water: a docking station, fog, a wider view
        apply_sea(spec, c.link.water_at_led.attenuation, centre, np.asarray(tx.pos),
                  config.depth)
    _set_yaw(tx, config.led_yaw, config.led_pitch)

    for axis in layout.axes:
        hinge = spec.joint(axis.joint)
        hinge.damping = [config.gimbal_damping, 0.0, 0.0]  # MuJoCo 4: damping polynomial
        motor = spec.actuator(axis.motor)
        motor.ctrlrange = [-config.torque_limit, config.torque_limit]
        motor.forcerange = [-config.torque_limit, config.torque_limit]
        motor.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        motor.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    if config.hull_mass is not None:
        spec.geom("hull").mass = config.hull_mass
    return spec


def shelter(spec: mujoco.MjSpec, bodies) -> None:
    """Keep the water's flow off ``bodies`` (a head in a dome). A body none of whose
    geoms has a fluid shape takes MuJoCo's inertia-box fluid model, and an ellipsoid's
    added mass turns it whatever its coefficients (the Munk moment: 17 mN m on the
    housing abeam at 1 m/s), so each body's geoms lose their fluid shape and it gets one
    massless 0.1 mm marker with the ellipsoid model and zero coefficients."""
    for body in bodies:
        for g in body.geoms:
            g.fluid_ellipsoid = 0
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[1e-4, 0, 0], density=0.0,
                      contype=0, conaffinity=0, group=3, fluid_ellipsoid=1,
                      fluid_coefs=[0.0] * 5)


def set_buoyancy(m: mujoco.MjModel, auv: int, gimbal: int, water_density: float) -> None:
    """Buoyancy = displaced water weight: gravcomp = rho V / m for the hull body ``auv``.
    V counts the geoms the water acts on (fluid forces on), not eye-only trim; the
    gimbal (body ``gimbal``) floats whenever there is water."""
    volume = 0.0
    for g in np.flatnonzero((m.geom_bodyid == auv) & (m.geom_fluid[:, 0] > 0)):
        size = m.geom_size[g]
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            volume += 4.0 / 3.0 * math.pi * float(np.prod(size))
        elif m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
            volume += 8.0 * float(np.prod(size))
    m.body_gravcomp[auv] = water_density * volume / m.body_mass[auv]
    m.body_gravcomp[gimbal] = 1.0 if water_density > 0 else 0.0
