"""The MuJoCo world: an AUV with a receiver gimbal, an LED transmitter and an occluder.

The scene lives in ``assets/led_link.xml``; :class:`LinkWorld` loads it with
``mujoco.MjSpec``, applies a :class:`WorldConfig` (link distance, photodiode offset,
LED pose, hull mass, water, torque limit) and exposes named accessors.

=====================  ==========================================  ========
accessor               meaning                                     unit
=====================  ==========================================  ========
gimbal_angle           hinge angle q of the receiver gimbal        rad
gimbal_rate            dq/dt                                       rad/s
torque                 commanded gimbal motor torque               N m
photodiode_pos(i)      position of photodiode i (0 or 1)           m
photodiode_normal(i)   unit normal of photodiode i                 -
led_pos, led_axis      LED position and unit emission axis         m, -
=====================  ==========================================  ========
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from .config import ConfigError, LinkConstants

ASSETS = Path(__file__).resolve().parent.parent / "assets"
SCENE = ASSETS / "led_link.xml"


class WorldError(ValueError):
    """The scene cannot be built as asked (bad file, name, or geometry)."""


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
    """

    constants: LinkConstants = field(default_factory=LinkConstants)
    xml: Path = SCENE
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

    def __post_init__(self):
        checks = [
            ("torque_limit", self.torque_limit, self.torque_limit > 0, "> 0 N m"),
            ("water_density", self.water_density, self.water_density >= 0, ">= 0 kg/m^3"),
            ("water_viscosity", self.water_viscosity, self.water_viscosity >= 0, ">= 0 Pa s"),
            ("gimbal_damping", self.gimbal_damping, self.gimbal_damping >= 0, ">= 0 N m s/rad"),
            ("timestep", self.timestep, 0 < self.timestep <= self.constants.Te,
             f"in (0, Te={self.constants.Te}] s"),
            ("n_rays", self.n_rays, self.n_rays >= 1, ">= 1"),
            ("aperture_radius", self.aperture_radius, self.aperture_radius >= 0, ">= 0 m"),
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
    if not path.is_file():
        raise WorldError(f"scene file {str(path)!r} does not exist")
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as exc:  # mujoco raises ValueError with the parser message
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise WorldError(f"scene file {str(path)!r} is not valid MJCF: {first}") from None
    for kind, name in [("body", "auv"), ("body", "gimbal"), ("body", "transmitter"),
                       ("body", "occluder"), ("site", "pd1"), ("site", "pd2"),
                       ("site", "led"), ("joint", "gimbal_hinge"),
                       ("actuator", "gimbal_motor"), ("geom", "hull")]:
        if getattr(spec, kind)(name) is None:
            raise WorldError(f"scene file {str(path)!r} has no {kind} named {name!r}")
    c = config.constants
    spec.option.timestep = config.timestep
    spec.option.density = config.water_density
    spec.option.viscosity = config.water_viscosity

    # Photodiode 2's normal is photodiode 1's turned by -dphi about the hinge axis, so
    # its incidence angle is phi + dphi (paper eq. eq-4a).
    pd1, pd2 = spec.site("pd1"), spec.site("pd2")
    normal2 = _rotate_z([1.0, 0.0, 0.0], -c.dphi)
    _set_zaxis(pd2, normal2)
    lens2 = spec.geom("pd2_lens")
    if lens2 is not None:
        _set_zaxis(lens2, normal2)

    # LED at distance d in front of the receiver centre (midpoint of the photodiodes).
    gimbal = spec.body("gimbal")
    centre_local = 0.5 * (np.asarray(pd1.pos) + np.asarray(pd2.pos))
    centre = np.asarray(gimbal.pos) + centre_local
    tx = spec.body("transmitter")
    tx.pos = [centre[0] + c.distance, centre[1] + config.led_lateral_offset, centre[2]]
    _set_yaw(tx, config.led_yaw)

    hinge = spec.joint("gimbal_hinge")
    hinge.damping = [config.gimbal_damping, 0.0, 0.0]  # MuJoCo 4: damping polynomial
    motor = spec.actuator("gimbal_motor")
    motor.ctrlrange = [-config.torque_limit, config.torque_limit]
    motor.forcerange = [-config.torque_limit, config.torque_limit]
    motor.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    motor.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    if config.hull_mass is not None:
        spec.geom("hull").mass = config.hull_mass
    return spec


class LinkWorld:
    """The compiled scene plus named accessors; see the module docstring."""

    def __init__(self, config: WorldConfig | None = None):
        self.config = config or WorldConfig()
        self.spec = build_spec(self.config)
        try:
            self.model = self.spec.compile()
        except Exception as exc:
            raise WorldError(f"scene does not compile: {str(exc).strip().splitlines()[0]}") \
                from None
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.auv_id = m.body("auv").id
        self.gimbal_id = m.body("gimbal").id
        self.transmitter_id = m.body("transmitter").id
        self.occluder_id = m.body("occluder").id
        self.tx_mocap = m.body_mocapid[self.transmitter_id]
        self.occluder_mocap = m.body_mocapid[self.occluder_id]
        self.pd_ids = (m.site("pd1").id, m.site("pd2").id)
        self.led_id = m.site("led").id
        hinge = m.joint("gimbal_hinge")
        self.hinge_qpos = hinge.qposadr[0]
        self.hinge_dof = hinge.dofadr[0]
        self.motor_id = m.actuator("gimbal_motor").id
        self._set_hull_buoyancy()
        self.transmitter_home = self.data.mocap_pos[self.tx_mocap].copy()
        self.occluder_home = self.data.mocap_pos[self.occluder_mocap].copy()
        self.transmitter_velocity = np.zeros(3)  # set by disturbances that move it
        mujoco.mj_forward(m, self.data)
        self.initial_hull_pos = self.data.xpos[self.auv_id].copy()

    def _set_hull_buoyancy(self) -> None:
        """Buoyancy = displaced water weight: gravcomp = rho V / m for the hull body."""
        m = self.model
        rho = self.config.water_density
        volume = 0.0
        for g in np.flatnonzero(m.geom_bodyid == self.auv_id):
            size = m.geom_size[g]
            if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
                volume += 4.0 / 3.0 * math.pi * float(np.prod(size))
            elif m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
                volume += 8.0 * float(np.prod(size))
        m.body_gravcomp[self.auv_id] = rho * volume / m.body_mass[self.auv_id]
        m.body_gravcomp[self.gimbal_id] = 1.0 if rho > 0 else 0.0

    # -- state ---------------------------------------------------------------------------

    def reset(self, gimbal_angle: float = 0.0, gimbal_rate: float = 0.0) -> None:
        """Back to the initial pose with the given gimbal state."""
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self.hinge_qpos] = gimbal_angle
        self.data.qvel[self.hinge_dof] = gimbal_rate
        self.data.mocap_pos[self.tx_mocap] = self.transmitter_home
        self.data.mocap_pos[self.occluder_mocap] = self.occluder_home
        self.transmitter_velocity[:] = 0
        self.model.opt.wind[:] = 0
        mujoco.mj_forward(self.model, self.data)

    @property
    def gimbal_angle(self) -> float:
        return float(self.data.qpos[self.hinge_qpos])

    @property
    def gimbal_rate(self) -> float:
        return float(self.data.qvel[self.hinge_dof])

    @property
    def torque(self) -> float:
        return float(self.data.ctrl[self.motor_id])

    def set_torque(self, torque: float) -> float:
        """Command the gimbal motor; clipped to the torque limit. Returns what was applied."""
        lim = self.config.torque_limit
        applied = min(max(float(torque), -lim), lim)
        self.data.ctrl[self.motor_id] = applied
        return applied

    def step(self, n: int | None = None) -> None:
        """Advance ``n`` physics steps (default: one control period Te)."""
        mujoco.mj_step(self.model, self.data, nstep=n or self.config.substeps)

    @property
    def time(self) -> float:
        return float(self.data.time)

    # -- geometry -----------------------------------------------------------------------

    def photodiode_pos(self, i: int) -> np.ndarray:
        return self.data.site_xpos[self.pd_ids[i]]

    def photodiode_normal(self, i: int) -> np.ndarray:
        return self.data.site_xmat[self.pd_ids[i]].reshape(3, 3)[:, 2]

    @property
    def led_pos(self) -> np.ndarray:
        return self.data.site_xpos[self.led_id]

    @property
    def led_axis(self) -> np.ndarray:
        return self.data.site_xmat[self.led_id].reshape(3, 3)[:, 2]

    @property
    def hinge_axis(self) -> np.ndarray:
        return self.data.xmat[self.gimbal_id].reshape(3, 3)[:, 2]

    @property
    def hull_pos(self) -> np.ndarray:
        return self.data.xpos[self.auv_id]

    def body_velocity(self, body_id: int) -> np.ndarray:
        """(angular, linear) velocity of a body in the world frame, shape (6,)."""
        res = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_BODY, body_id,
                                 res, 0)
        return res

    def site_velocity(self, site_id: int) -> np.ndarray:
        res = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_SITE, site_id,
                                 res, 0)
        return res

    def set_occluder(self, pos) -> None:
        self.data.mocap_pos[self.occluder_mocap] = pos

    def set_transmitter(self, pos, velocity=(0.0, 0.0, 0.0)) -> None:
        self.data.mocap_pos[self.tx_mocap] = pos
        self.transmitter_velocity[:] = velocity

    def link_midpoint(self) -> np.ndarray:
        """Middle of the line of sight between the receiver centre and the LED."""
        centre = 0.5 * (self.photodiode_pos(0) + self.photodiode_pos(1))
        return 0.5 * (centre + self.led_pos)
