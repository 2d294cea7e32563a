"""The gimbal's part of :class:`~ledsim.physics.world.LinkWorld`: its axes' angles, rates
and motors, each a float for the first axis (the paper's one, where a float is what the
control step reads) and an array over the layout's axes (:mod:`ledsim.physics.layout`)."""

from __future__ import annotations

import mujoco
import numpy as np


class GimbalAccess:
    """Accessors of the receiver gimbal, mixed into ``LinkWorld`` (which gives ``model``,
    ``data``, ``config``, ``ids`` and the first axis's ``_hinge_qpos``, ``_hinge_dof``
    and ``_motor``)."""

    # -- the first axis, in floats ------------------------------------------------------

    @property
    def gimbal_angle(self) -> float:
        return float(self.data.qpos[self._hinge_qpos])

    @property
    def gimbal_rate(self) -> float:
        return float(self.data.qvel[self._hinge_dof])

    @property
    def torque(self) -> float:
        return float(self.data.ctrl[self._motor])

    def set_torque(self, torque: float) -> float:
        """Command the gimbal motor; clipped to the torque limit. Returns what was applied."""
        lim = self.config.torque_limit
        applied = min(max(float(torque), -lim), lim)
        self.data.ctrl[self._motor] = applied
        return applied

    # -- every axis, as arrays over the layout's axes ------------------------------------

    @property
    def n_axes(self) -> int:
        return len(self.ids.axes_qpos)

    @property
    def gimbal_angles(self) -> np.ndarray:
        """Each axis's hinge angle [rad], shape (n_axes,)."""
        return self.data.qpos[list(self.ids.axes_qpos)].copy()

    @property
    def gimbal_rates(self) -> np.ndarray:
        """Each axis's hinge rate [rad/s], shape (n_axes,)."""
        return self.data.qvel[list(self.ids.axes_dof)].copy()

    @property
    def torques(self) -> np.ndarray:
        """Each axis's motor torque [N m], shape (n_axes,)."""
        return self.data.ctrl[list(self.ids.motors)].copy()

    def set_torques(self, torques) -> np.ndarray:
        """Command every axis's motor [N m], shape (n_axes,); each clipped to the torque
        limit. Returns what was applied."""
        t = np.asarray(torques, dtype=float)
        if t.shape != (self.n_axes,):
            raise ValueError(f"torques of shape {t.shape} for a gimbal of {self.n_axes} "
                             f"axes: give one per axis, shape ({self.n_axes},)")
        lim = self.config.torque_limit
        ctrl, out = self.data.ctrl, []
        # np.clip's values (NaN kept) in plain floats: numpy's calls cost 5x the rest.
        for m, x in zip(self.ids.motors, t.tolist(), strict=True):
            ctrl[m] = v = -lim if x < -lim else (lim if x > lim else x)
            out.append(v)
        return np.array(out)

    def encoder_readings(self) -> np.ndarray:
        """Each axis's encoder (MuJoCo ``jointpos`` sensor) [rad], shape (n_axes,), at the
        current state (NaN for an axis whose scene has no encoder)."""
        mujoco.mj_sensorPos(self.model, self.data)  # writes sensordata only
        adr = self.ids.encoders
        return np.array([self.data.sensordata[a] if a >= 0 else np.nan for a in adr])

    def _set_gimbal(self, angle, rate) -> None:
        """The gimbal's state: a float for the first axis, or an array over the axes."""
        if np.ndim(angle) == 0 and np.ndim(rate) == 0:
            self.data.qpos[self._hinge_qpos] = angle
            self.data.qvel[self._hinge_dof] = rate
        else:
            self.data.qpos[list(self.ids.axes_qpos)] = angle
            self.data.qvel[list(self.ids.axes_dof)] = rate

    def add_angular_rate(self, rate: float, hull: bool = False, axis: str = "yaw") -> None:
        """An angular-rate impulse [rad/s]: to the gimbal hinge, or (``hull``) to the
        AUV about its own ``axis`` (``roll``, ``pitch`` or ``yaw``: x, y or z of the hull's
        frame, in which MuJoCo's free joint keeps its angular velocity)."""
        if hull:  # free joint: (v, omega), omega in the body's frame
            self.data.qvel[self._hull_dof + 3 + ("roll", "pitch", "yaw").index(axis)] += rate
        else:
            self.data.qvel[self._hinge_dof] += rate

    def hinge_inertia(self, axis: int = 0) -> float:
        """Gimbal inertia about an axis's hinge incl. armature [kg m^2] (MuJoCo's mass
        matrix; the first axis unless told)."""
        mujoco.mj_forward(self.model, self.data)
        M = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, self.data, M)
        dof = self.ids.axes_dof[axis]
        return float(M[dof, dof])
