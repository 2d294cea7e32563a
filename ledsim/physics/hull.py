"""The hull's part of :class:`~ledsim.physics.world.LinkWorld`: its pose and velocity,
its own sensors (MuJoCo's gyro, accelerometer, velocimeter, jointpos, framepos), its
thrusters, and the external wrench the disturbances put on it."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ledsim.physics.scene_ids import VehicleMotion


class HullAccess:
    """Accessors of the AUV's hull, mixed into ``LinkWorld`` (which gives ``model``,
    ``data``, ``ids`` and ``_velocity``)."""

    @property
    def hull_pos(self) -> np.ndarray:
        return self.data.xpos[self.ids.hull_body]

    @property
    def hull_yaw(self) -> float:
        """Heading of the AUV about world z [rad]."""
        R = self.data.xmat[self.ids.hull_body]
        return math.atan2(R[3], R[0])

    def hull_velocity(self) -> np.ndarray:
        """(angular, linear) velocity of the hull in the world frame, shape (6,)."""
        return self._velocity(mujoco.mjtObj.mjOBJ_BODY, self.ids.hull_body)

    def vehicle_motion(self) -> VehicleMotion | None:
        """The vehicle's own sensors, noise-free, at the current state (None: the scene
        has none); :class:`~ledsim.physics.nav_sensors.NavigationSensor` adds the noise."""
        adr = self.ids.vehicle_sensors
        if adr is None:
            return None
        m, d = self.model, self.data
        mujoco.mj_sensorPos(m, d)  # writes sensordata only: the dynamics are untouched
        mujoco.mj_sensorVel(m, d)
        s, (g, a, v, e, p) = d.sensordata, adr
        mag = self.ids.magnetometer
        return VehicleMotion(s[g:g + 3].copy(), s[a:a + 3].copy(), s[v:v + 3].copy(),
                             float(s[e]), s[p:p + 3].copy(),
                             None if mag is None else s[mag:mag + 3].copy())

    @property
    def magnetic_field(self) -> np.ndarray:
        """The Earth's magnetic field of the scene, world frame [T] (``opt.magnetic``):
        what a vehicle's designer knows from a field model."""
        return self.model.opt.magnetic.copy()

    def usbl_range(self) -> float | None:
        """Slant range from the USBL transceiver (the scene's ``usbl`` site) to the hull
        [m] (None: the scene has none)."""
        site = self.ids.usbl_site
        if site is None:
            return None
        return float(np.linalg.norm(self.data.site_xpos[site] - self.hull_pos))

    def set_thrust(self, command) -> np.ndarray:
        """Command the hull's surge, sway and heave thrust [N] and pitch and yaw torque
        [N m] (hull frame), each clipped at its thruster's limit. Returns what was
        applied."""
        ids, lo, hi = self._thruster_range()
        ctrl = self.data.ctrl
        # np.clip's values (NaN kept) in plain floats: numpy's calls cost 5x the rest.
        out = []
        for i, x, a, b in zip(ids, np.asarray(command, dtype=float).tolist(), lo, hi,
                              strict=True):
            ctrl[i] = v = a if x < a else (b if x > b else x)
            out.append(v)
        return np.array(out)

    def _thruster_range(self) -> tuple[list, list, list]:
        """(actuator ids, lower limits, upper limits) of the thrusters (the model's
        ``ctrlrange``, read once), as lists."""
        return self._thruster_cache()[:3]

    def thruster_bounds(self) -> tuple:
        """(where the thrusters sit in ``data.ctrl``: a slice when their ids are
        consecutive, else the ids; their lower and upper limits [N, N m] as arrays),
        read once from the model's ``ctrlrange``."""
        return self._thruster_cache()[3:6]

    def _thruster_cache(self) -> tuple:
        """:meth:`_thruster_range`, then :meth:`thruster_bounds`, then the model they
        were read from."""
        cached = getattr(self, "_thrusters_cached", None)
        if cached is None or cached[-1] is not self.model:
            ids = np.array(self.ids.thrusters)
            lo, hi = self.model.actuator_ctrlrange[ids].T.tolist()
            ids = ids.tolist()
            run = ids == list(range(ids[0], ids[0] + len(ids)))
            where = slice(ids[0], ids[0] + len(ids)) if run else ids
            cached = self._thrusters_cached = (ids, lo, hi, where, np.array(lo),
                                               np.array(hi), self.model)
        return cached

    def thrust_limits(self) -> np.ndarray:
        """The thrusters' limits: surge, sway, heave [N], pitch and yaw [N m] (their
        ``ctrlrange``; zeros: none)."""
        ids = self.ids.thrusters
        if ids is None:
            return np.zeros(5)
        return np.abs(self.model.actuator_ctrlrange[list(ids)]).max(axis=1)

    @property
    def thrust(self) -> np.ndarray:
        """The thrusters' commands: surge, sway, heave [N], pitch and yaw [N m] (zeros:
        none)."""
        ids = self.ids.thrusters
        return np.zeros(5) if ids is None else self.data.ctrl[list(ids)].copy()

    def clear_hull_wrench(self) -> None:
        """Start a control step's external wrench on the hull: buoyancy's righting moment
        only, ``B BG (z_hull x z_world)`` (B: the buoyancy [N], BG: the metacentric
        height [m]), which MuJoCo's gravity compensation at the centre of mass lacks."""
        hull = self.ids.hull_body
        m = self.model
        key = (float(m.body_gravcomp[hull]), m)  # the buoyancy may change (set_hull_buoyancy)
        cached = getattr(self, "_righting", None)
        if cached is None or cached[0] != key[0] or cached[1] is not m:
            k = float(m.body_mass[hull] * m.body_gravcomp[hull]) * math.sqrt(
                float(m.opt.gravity @ m.opt.gravity)) * self.config.metacentric_height
            cached = self._righting = (*key, k)
        k = cached[2]
        R = self.data.xmat[hull]  # z_hull = (R[2], R[5], R[8]); z_hull x z = (R[5], -R[2], 0)
        xfrc = self.data.xfrc_applied[hull]
        xfrc[:] = (0.0, 0.0, 0.0, k * R[5], -k * R[2], 0.0)

    def add_hull_wrench(self, force=(0.0, 0.0, 0.0), torque=(0.0, 0.0, 0.0)) -> None:
        """Add a force [N] and torque [N m] (world frame, at the hull's centre of mass)."""
        xfrc = self.data.xfrc_applied[self.ids.hull_body]
        xfrc[:3] += force
        xfrc[3:] += torque

    def set_hull_buoyancy(self, fraction: float) -> None:
        """Share of the hull's weight carried by buoyancy (1: neutrally buoyant) [-]."""
        self.model.body_gravcomp[self.ids.hull_body] = fraction

    @property
    def hull_rotation(self) -> np.ndarray:
        """The hull's frame in the world, 3x3 (columns: its axes)."""
        return self.data.xmat[self.ids.hull_body].reshape(3, 3).copy()

    def site_in_hull(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """A site's frame (3x3) and position [m] in the hull's frame: the lever arms a
        vehicle knows from its drawings."""
        R = self.hull_rotation
        site = self.model.site(name).id
        frame = R.T @ self.data.site_xmat[site].reshape(3, 3)
        return frame, R.T @ (self.data.site_xpos[site] - self.hull_pos)

    def gimbal_in_hull(self) -> np.ndarray:
        """The gimbal hinge's position in the hull's frame [m]."""
        return self.hull_rotation.T @ (self.data.xpos[self.ids.gimbal_body] - self.hull_pos)

    def hull_inertia(self) -> np.ndarray:
        """The hull's mass [kg] (surge, sway, heave) and pitch and yaw inertia [kg m^2],
        the gimbal included (MuJoCo's mass matrix at the current pose): what its
        designer knows."""
        mujoco.mj_forward(self.model, self.data)
        M = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, self.data, M)
        dof = self.model.jnt_dofadr[self.model.body_jntadr[self.ids.hull_body]]
        return np.diag(M)[[dof, dof + 1, dof + 2, dof + 4, dof + 5]].copy()


def set_thrust_rows(worlds, command: np.ndarray) -> np.ndarray:
    """:meth:`HullAccess.set_thrust` of every world: row i of ``command`` (N, 5) [N, N m]
    to ``worlds[i]``, clipped at its thrusters' limits, all rows at once (its values:
    a NaN kept, each limit where a command passes it). Returns what was applied,
    (N, 5)."""
    if len(worlds) == 1:  # plain floats beat numpy's calls for one
        return worlds[0].set_thrust(command[0])[None]
    bounds = [w.thruster_bounds() for w in worlds]
    lo = np.array([b[1] for b in bounds])
    hi = np.array([b[2] for b in bounds])
    x = np.asarray(command, dtype=float)
    applied = np.where(x < lo, lo, np.where(x > hi, hi, x))
    for w, b, row in zip(worlds, bounds, applied, strict=True):
        w.data.ctrl[b[0]] = row
    return applied


def vehicle_motion_rows(worlds) -> tuple[VehicleMotion, np.ndarray, np.ndarray]:
    """:meth:`HullAccess.vehicle_motion` of every world (of one scene layout) as one
    :class:`VehicleMotion` of arrays with a leading axis of N (``encoder`` (N,)), and
    the hulls' rotations (N, 3, 3) and linear velocities in the world frame (N, 3)
    [m/s] (:attr:`HullAccess.hull_rotation`, :meth:`HullAccess.hull_velocity`'s): each
    world's values, copied once per world instead of once per field."""
    w0 = worlds[0]
    layout = w0.ids.vehicle_sensors, w0.ids.magnetometer, w0.ids.hull_body
    for w in worlds:
        ids = w.ids
        if (ids.vehicle_sensors, ids.magnetometer, ids.hull_body) != layout:
            raise ValueError("the worlds' vehicle sensors are not at the same addresses: "
                             "read each world's vehicle_motion() instead")
    (g, a, v, e, p), mag, hull = layout
    n = len(worlds)
    sensed = np.empty((n, w0.model.nsensordata))
    rotation = np.empty((n, 9))
    velocity = np.empty((n, 6))
    body = mujoco.mjtObj.mjOBJ_BODY
    for i, w in enumerate(worlds):
        m, d = w.model, w.data
        mujoco.mj_sensorPos(m, d)  # writes sensordata only: the dynamics are untouched
        mujoco.mj_sensorVel(m, d)
        sensed[i] = d.sensordata
        rotation[i] = d.xmat[hull]
        mujoco.mj_objectVelocity(m, d, body, hull, velocity[i], 0)
    motion = VehicleMotion(sensed[:, g:g + 3].copy(), sensed[:, a:a + 3].copy(),
                           sensed[:, v:v + 3].copy(), sensed[:, e].copy(),
                           sensed[:, p:p + 3].copy(),
                           None if mag is None else sensed[:, mag:mag + 3].copy())
    return motion, rotation.reshape(n, 3, 3), velocity[:, 3:].copy()
