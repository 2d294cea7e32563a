"""The MuJoCo world: an AUV with a receiver gimbal, an LED transmitter and an occluder.

:class:`LinkWorld` compiles the scene (:mod:`ledsim.physics.scene`) and is the only
code that touches MuJoCo's ids and arrays: the sensor, the disturbances, the loop and the
renderer use the named methods below.

=======================  ==========================================  ===========
accessor                 meaning                                     unit
=======================  ==========================================  ===========
gimbal_angle, _rate      hinge angle q of the receiver gimbal, dq/dt  rad, rad/s
torque, set_torque       gimbal motor torque (clipped at the limit)  N m
gimbal_angles, _rates    every axis's q and dq/dt (arrays; gimbal.py)  rad, rad/s
torques, set_torques     every axis's motor torque (arrays)          N m
photodiode_pos(i)        position of photodiode i (0 or 1)           m
photodiode_normal(i)     unit normal of photodiode i                 -
photodiode_velocity(i)   (angular, linear) velocity of photodiode i  rad/s, m/s
led_pos, led_rotation    LED position and orientation (z: its axis)  m, -
hinge_axis               the gimbal's rotation axis                  -
hull_pos, hull_yaw       AUV position and heading                    m, rad
hull_velocity            (angular, linear) velocity of the hull      rad/s, m/s
vehicle_motion           IMU, DVL, encoder, position (noise-free)    SI
add_hull_wrench          force and torque on the hull this step      N, N m
set_thrust, thrust       surge, sway, heave; pitch, yaw thrusters    N; N m
set_current              water velocity (MuJoCo's medium velocity)   m/s
set_transmitter          LED platform pose and velocity              m, rad, m/s
set_occluder             occluder plate position                     m
dvl_bottom_lock          the DVL sees the seabed (False: no pings)   -
cast_rays                where rays from a point are stopped          m
=======================  ==========================================  ===========
"""

from __future__ import annotations

import logging
import math
from contextlib import contextmanager

import mujoco
import numpy as np

from ledsim.physics.gimbal import GimbalAccess
from ledsim.physics.hull import HullAccess
from ledsim.physics.scene import SCENE, WorldConfig, WorldError, build_spec, set_buoyancy
from ledsim.physics.scene_ids import SceneIds

__all__ = ["LinkWorld", "WorldConfig", "WorldError", "SCENE"]

RAY_GROUPS = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)  # groups 0-2 block light
_UNSTABLE = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL,
             mujoco.mjtWarning.mjWARN_BADQPOS)
_AUTORESET_OFF = mujoco.mjtDisableBit.mjDSBL_AUTORESET
_log = logging.getLogger("ledsim.mujoco")


def _route_mujoco_warnings() -> None:
    """MuJoCo's warnings to Python logging, not MUJOCO_LOG.TXT (unless already routed)."""
    if mujoco.get_mju_user_warning() is None:
        mujoco.set_mju_user_warning(_on_mujoco_warning)


def _on_mujoco_warning(msg: str) -> None:
    # An unstable simulation becomes a one-line WorldError; MuJoCo's message: debug.
    level = logging.DEBUG if "unstable" in msg else logging.WARNING
    _log.log(level, "MuJoCo: %s", msg.strip())


class LinkWorld(HullAccess, GimbalAccess):
    """The compiled scene plus named accessors; see the module docstring."""

    def __init__(self, config: WorldConfig | None = None, *,
                 share_model_of: LinkWorld | None = None):
        _route_mujoco_warnings()
        if share_model_of is not None:  # a batch's worlds: one model, each its own data
            self.config, self.spec = share_model_of.config, share_model_of.spec
            self.model = share_model_of.model
        else:
            self.config = config or WorldConfig()
            self.spec = build_spec(self.config)
            try:
                self.model = self.spec.compile()
            except Exception as e:
                raise WorldError(f"scene does not compile: {str(e).strip().splitlines()[0]}")\
                    from None
        self.data = mujoco.MjData(self.model)
        self._substeps, self._dt = self.config.substeps, float(self.model.opt.timestep)
        self._no_autoreset = bool(self.model.opt.disableflags & _AUTORESET_OFF)
        m = self.model
        #: Named MuJoCo ids and addresses, for code that works on MuJoCo's arrays.
        self.ids = ids = SceneIds.of(m, self.config.constants.layout)
        self._auv, self._gimbal = ids.hull_body, ids.gimbal_body
        self._tx_mocap = m.body_mocapid[m.body("transmitter").id]
        self._occluder_mocap = m.body_mocapid[m.body("occluder").id]
        self._pd, self._led = ids.photodiode_sites, ids.led_site
        self._hinge_qpos, self._hinge_dof, self._motor = ids.hinge_qpos, ids.hinge_dof, ids.motor
        self._hull_dof = m.jnt_dofadr[m.body_jntadr[self._auv]]  # the free joint's first dof
        if share_model_of is None:
            set_buoyancy(m, self._auv, self._gimbal, self.config.water_density)
        self.transmitter_home = self.data.mocap_pos[self._tx_mocap].copy()
        self.occluder_home = self.data.mocap_pos[self._occluder_mocap].copy()
        self.occluder_half_size = float(m.geom("occluder_plate").size[2])  # m
        self.transmitter_velocity = np.zeros(3)  # set by disturbances that move it
        self._current, self._wave_flow = np.zeros(3), np.zeros(3)  # opt.wind's parts
        #: The light around the receiver (:mod:`ledsim.physics.light`): a factor on each
        #: photodiode's LED power and watts added to each sample (None: none).
        self.light_gain: np.ndarray | None = None
        self.light_noise: np.ndarray | None = None
        #: The DVL has bottom lock (a dropout disturbance takes it away for a while).
        self.dvl_bottom_lock = True
        self._ray_buffers: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        mujoco.mj_forward(m, self.data)
        self.initial_hull_pos = self.data.xpos[self._auv].copy()

    # -- state and stepping ----------------------------------------------------------------

    def reset(self, gimbal_angle: float = 0.0, gimbal_rate: float = 0.0) -> None:
        """Back to the initial pose with the given gimbal state [rad, rad/s]: the first
        axis's (floats) or every axis's (arrays over the axes)."""
        mujoco.mj_resetData(self.model, self.data)
        self._set_gimbal(gimbal_angle, gimbal_rate)
        self.data.mocap_pos[self._tx_mocap] = self.transmitter_home
        self.data.mocap_pos[self._occluder_mocap] = self.occluder_home
        self.transmitter_velocity[:] = 0
        self.dvl_bottom_lock = True
        self.model.opt.wind[:] = 0
        self._current, self._wave_flow = np.zeros(3), np.zeros(3)
        self.light_gain = self.light_noise = None
        mujoco.mj_forward(self.model, self.data)

    def step(self, n: int | None = None) -> None:
        """Advance ``n`` physics steps (default: one control period Te).

        Raises :class:`WorldError` if the physics became unstable (MuJoCo would otherwise
        reset the state silently and go on)."""
        d, t0 = self.data, self.data.time
        n = n or self._substeps
        mujoco.mj_step(self.model, d, nstep=n)
        # An unstable substep makes MuJoCo reset the data (time to 0) and go on; reading
        # the warnings costs a tenth of a step, so only when time fell short, after a
        # first substep from 0, or always if the scene turned that reset off.
        if (self._no_autoreset or t0 < self._dt or d.time < t0 + (n - 0.5) * self._dt) \
                and any(d.warning[w].number for w in _UNSTABLE):
            raise WorldError(f"the physics became unstable after t = {t0:.3f} s (forces "
                             "or speeds out of range): reduce the disturbance")

    def forward_kinematics(self) -> None:
        """Poses and velocities of every body and site from the current qpos, qvel and
        mocap poses (what the sensor reads), without computing forces."""
        m, d = self.model, self.data
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_comVel(m, d)

    @property
    def time(self) -> float:
        return float(self.data.time)

    # -- geometry -----------------------------------------------------------------------

    def photodiode_pos(self, i: int) -> np.ndarray:
        return self.data.site_xpos[self._pd[i]]

    def photodiode_normal(self, i: int) -> np.ndarray:
        return self.data.site_xmat[self._pd[i]].reshape(3, 3)[:, 2]

    def photodiode_velocity(self, i: int) -> np.ndarray:
        """(angular, linear) velocity of photodiode i in the world frame, shape (6,)."""
        return self._velocity(mujoco.mjtObj.mjOBJ_SITE, self._pd[i])

    def _velocity(self, kind, index: int) -> np.ndarray:
        res = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, self.data, kind, index, res, 0)
        return res

    @property
    def led_pos(self) -> np.ndarray:
        return self.data.site_xpos[self._led]

    @property
    def led_rotation(self) -> np.ndarray:
        """LED frame as a 3x3 rotation matrix; its z column is the emission axis."""
        return self.data.site_xmat[self._led].reshape(3, 3)

    @property
    def hinge_axis(self) -> np.ndarray:
        return self.data.xmat[self._gimbal].reshape(3, 3)[:, 2]

    def link_midpoint(self) -> np.ndarray:
        """Middle of the line of sight between the receiver centre and the LED."""
        centre = 0.5 * (self.photodiode_pos(0) + self.photodiode_pos(1))
        return 0.5 * (centre + self.led_pos)

    def cast_rays(self, origin: np.ndarray, directions: np.ndarray,
                  max_length: float) -> np.ndarray:
        """Distance along each unit direction to the first light-blocking geom [m];
        -1 where nothing is hit within ``max_length``. The gimbal's own body and the
        optics (geom group 3) are ignored."""
        n = directions.size // 3
        if n not in self._ray_buffers:  # mj_multiRay wants outputs of exactly n entries
            self._ray_buffers[n] = (np.zeros(n, dtype=np.int32), np.zeros(n))
        geom, dist = self._ray_buffers[n]
        mujoco.mj_multiRay(self.model, self.data, origin, directions.ravel(), RAY_GROUPS, 1,
                           self._gimbal, geom, dist, None, n, max_length)
        return dist

    # -- water and the other bodies --------------------------------------------------------

    def set_current(self, velocity) -> None:
        """Velocity of the water [m/s] (MuJoCo's medium velocity, felt by fluid forces);
        a wave's flow (:meth:`set_wave_flow`) adds to it."""
        self._current = np.asarray(velocity, dtype=float)
        self.model.opt.wind[:] = self._current + self._wave_flow

    def set_wave_flow(self, velocity) -> None:
        """The waves' water velocity at the hull [m/s], added to the current in MuJoCo's
        medium velocity."""
        self._wave_flow = np.asarray(velocity, dtype=float)
        self.model.opt.wind[:] = self._current + self._wave_flow

    @property
    def current(self) -> np.ndarray:
        """The current's velocity [m/s] (without the waves')."""
        return self._current.copy()

    def set_transmitter(self, pos, velocity=(0.0, 0.0, 0.0), yaw: float | None = None) -> None:
        """Move the LED platform to ``pos`` [m], moving at ``velocity`` [m/s]; ``yaw``
        [rad] turns it about world z (None: leave its heading)."""
        self.data.mocap_pos[self._tx_mocap] = pos
        self.transmitter_velocity[:] = velocity
        if yaw is not None:
            self.data.mocap_quat[self._tx_mocap] = [math.cos(yaw / 2), 0.0, 0.0,
                                                    math.sin(yaw / 2)]

    def set_occluder(self, pos) -> None:
        """Move the occluder plate's centre to ``pos`` [m]."""
        self.data.mocap_pos[self._occluder_mocap] = pos

    @contextmanager
    def parked_occluder(self):
        """The occluder at its parking place for the duration of the block (kinematics
        updated on entry and exit)."""
        where = self.data.mocap_pos[self._occluder_mocap].copy()
        self.set_occluder(self.occluder_home)
        mujoco.mj_kinematics(self.model, self.data)
        try:
            yield
        finally:
            self.set_occluder(where)
            mujoco.mj_kinematics(self.model, self.data)

    def camera_names(self) -> list[str]:
        return [self.model.camera(i).name for i in range(self.model.ncam)]
