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
from typing import NamedTuple

import mujoco
import numpy as np

from ..config import ConfigError, LinkConstants
from ..errors import LedsimError
from ..layout import ReceiverLayout
from ..resources import scene_path

#: Former module-level name of the default scene.
SCENE = scene_path()


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
    """

    constants: LinkConstants = field(default_factory=LinkConstants)
    xml: Path = field(default_factory=scene_path)
    led_lateral_offset: float = 0.0
    led_yaw: float = 0.0
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
        ]
        if self.hull_mass is not None:
            checks.append(("hull_mass", self.hull_mass, self.hull_mass > 0, "> 0 kg"))
        for name, value, ok, allowed in checks:
            if not (ok and math.isfinite(value)):
                raise ConfigError(f"{name}={value!r} is not allowed: must be {allowed}")
        ratio = self.constants.Te / self.timestep
        if abs(ratio - round(ratio)) > 1e-9:
            raise ConfigError(f"timestep={self.timestep!r} is not allowed: Te="
                              f"{self.constants.Te} must be a whole multiple of it")

    @property
    def substeps(self) -> int:
        return round(self.constants.Te / self.timestep)


def _rotate_z(v, angle):
    c, s = math.cos(angle), math.sin(angle)
    return [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]


def _set_zaxis(element, direction) -> None:
    """Orient an MjSpec site/geom so its z axis is ``direction`` (overrides the XML's)."""
    element.alt.type = mujoco.mjtOrientation.mjORIENTATION_ZAXIS
    element.alt.zaxis = list(direction)


def _set_yaw(element, angle: float) -> None:
    element.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    element.quat = [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]


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
    layout = c.layout.validate()
    for kind, name in [("body", "auv"), ("body", "gimbal"), ("body", "transmitter"),
                       ("body", "occluder"),
                       *(("site", p.site) for p in layout.photodiodes), ("site", "led"),
                       *(("joint", a.joint) for a in layout.axes),
                       *(("actuator", a.motor) for a in layout.axes), ("geom", "hull")]:
        if getattr(spec, kind)(name) is None:
            raise WorldError(f"scene file {str(path)!r} has no {kind} named {name!r}")
    spec.option.timestep = config.timestep
    spec.option.integrator = INTEGRATORS[config.integrator]
    spec.option.density = config.water_density
    spec.option.viscosity = config.water_viscosity

    # Each photodiode's normal is the reference normal (+x of the gimbal) turned by
    # -offset about the hinge axis, so its incidence angle is phi + offset (paper eq.
    # eq-4a: offsets 0 and dphi). The reference photodiode keeps the scene's own normal.
    sites = [spec.site(p.site) for p in layout.photodiodes]
    for p, site in zip(layout.photodiodes, sites, strict=True):
        if p.offset == 0.0:
            continue
        normal = _rotate_z([1.0, 0.0, 0.0], -p.offset)
        _set_zaxis(site, normal)
        lens = spec.geom(f"{p.site}_lens")
        if lens is not None:
            _set_zaxis(lens, normal)

    # LED at distance d in front of the receiver centre (midpoint of the photodiodes).
    gimbal = spec.body("gimbal")
    centre_local = np.mean([np.asarray(site.pos) for site in sites], axis=0)
    centre = np.asarray(gimbal.pos) + centre_local
    tx = spec.body("transmitter")
    tx.pos = [centre[0] + c.distance, centre[1] + config.led_lateral_offset, centre[2]]
    _set_yaw(tx, config.led_yaw)

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


@dataclass(frozen=True)
class SceneIds:
    """MuJoCo ids and addresses of the scene's named parts, read once when it compiles
    (for code that works on MuJoCo's arrays directly: the world batch, the rollouts).

    Attributes:
        hull_body, gimbal_body: body ids of the AUV and of the receiver gimbal.
        photodiode_sites: site ids of the layout's photodiodes, in its order; led_site:
            the LED's site id.
        hinge_qpos, hinge_dof: the gimbal axis's hinge's address in qpos and in qvel.
        motor: actuator id of the gimbal axis's motor.
        vehicle_sensors: sensordata addresses of the vehicle's sensors, in the order of
            :data:`VEHICLE_SENSORS` (None: the scene lacks one of them).
        thrusters: actuator ids of the hull's surge, sway, heave, pitch and yaw thrusters
            (None: the scene lacks one of them).
        magnetometer: sensordata address of the IMU's magnetometer, the heading
            reference (None: the scene has none; the navigation then has no heading
            reference).
        usbl_site: site id of the USBL transceiver the acoustic fixes are measured from
            (None: the scene has none; a fix's error then does not grow with range).
        missing_sensors: names of :data:`VEHICLE_SENSORS` the scene lacks.
    """

    hull_body: int
    gimbal_body: int
    photodiode_sites: tuple[int, ...]
    led_site: int
    hinge_qpos: int
    hinge_dof: int
    motor: int
    vehicle_sensors: tuple[int, ...] | None = None
    thrusters: tuple[int, ...] | None = None
    magnetometer: int | None = None
    usbl_site: int | None = None
    missing_sensors: tuple[str, ...] = ()

    @classmethod
    def of(cls, m, layout: ReceiverLayout | None = None) -> SceneIds:
        """The ids of model ``m`` built for the receiver ``layout`` (None: the paper's)."""
        layout = LinkConstants().layout if layout is None else layout
        (axis,) = layout.validate().axes
        hinge = m.joint(axis.joint)
        sensors = [m.sensor(i).name for i in range(m.nsensor)]
        missing = tuple(n for n in VEHICLE_SENSORS if n not in sensors)
        adr = None if missing else tuple(int(m.sensor(n).adr[0]) for n in VEHICLE_SENSORS)
        actuators = [m.actuator(i).name for i in range(m.nu)]
        thrusters = (tuple(int(m.actuator(n).id) for n in THRUSTERS)
                     if all(n in actuators for n in THRUSTERS) else None)
        mag = int(m.sensor(MAGNETOMETER).adr[0]) if MAGNETOMETER in sensors else None
        sites = [m.site(i).name for i in range(m.nsite)]
        usbl = int(m.site("usbl").id) if "usbl" in sites else None
        return cls(int(m.body("auv").id), int(m.body("gimbal").id),
                   tuple(int(m.site(p.site).id) for p in layout.photodiodes),
                   int(m.site("led").id), int(hinge.qposadr[0]), int(hinge.dofadr[0]),
                   int(m.actuator(axis.motor).id), adr, thrusters, mag, usbl, missing)


#: The vehicle's MuJoCo sensors by name: the IMU's gyro and accelerometer, the DVL (a
#: velocimeter), the gimbal's encoder (jointpos) and the acoustic position fix (framepos).
VEHICLE_SENSORS = ("imu_gyro", "imu_accel", "dvl_velocity", "gimbal_encoder",
                   "acoustic_fix")
#: The IMU's magnetometer, the navigation's heading reference (optional in a scene).
MAGNETOMETER = "imu_magnetometer"


#: The hull's thrusters by name: surge, sway and heave forces [N], pitch and yaw
#: torques [N m].
THRUSTERS = ("thruster_surge", "thruster_sway", "thruster_heave", "thruster_pitch",
             "thruster_yaw")


class VehicleMotion(NamedTuple):
    """The noise-free values of the vehicle's sensors at one instant (SI units).

    Attributes:
        gyro: hull angular velocity in the IMU frame [rad/s], (3,).
        accel: specific force in the IMU frame [m/s^2], (3,) (from the last physics step).
        dvl: hull velocity at the DVL in its frame [m/s], (3,) (z points down).
        encoder: the gimbal hinge angle [rad].
        position: the IMU's position in the world frame [m], (3,).
        magnetometer: the magnetic field in the IMU frame [T], (3,) (None: the scene
            has no magnetometer).
    """

    gyro: np.ndarray
    accel: np.ndarray
    dvl: np.ndarray
    encoder: float
    position: np.ndarray
    magnetometer: np.ndarray | None = None

