"""f and h of :class:`~ledsim.physics.gimbal_system.GimbalSystem` for many states at once.

Training data (``scripts/train_mujoco.py``) and the identified model's fit ask the
simulator for thousands of transitions. One at a time, each is a reset, five substeps
and a sensor read through Python (about 80 us). Here:

* ``f``: the substeps of every state run in ``mujoco.rollout`` (C, on ``threads``
  threads, one ``MjData`` per thread), from the state :meth:`LinkWorld.reset` gives
  with the same torque; the end states then go through a :class:`WorldBatch` for the
  kinematics and :meth:`BatchSensor.incidence_rate0` for phidot.
* ``h``: the worlds of a :class:`WorldBatch` are set to the states a reset gives and
  read by the vectorised :class:`BatchSensor` (rays only where a geom can block the
  beam).

Both give the one-at-a-time numbers (``tests/test_batch_system.py``).
"""

from __future__ import annotations

import mujoco
import numpy as np
from mujoco import rollout

from ledsim.physics.batch import WorldBatch
from ledsim.physics.batch_sensor import BatchSensor
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld, WorldError

FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS


class GimbalBatch:
    """Batched ``f`` and ``h`` of one :class:`GimbalSystem`'s world.

    Args:
        world: the system's world (its model is shared; not stepped here).
        phi_home: phi [rad] at gimbal angle 0.
        threads: threads for ``mujoco.rollout`` (the physics).
        block: worlds in the batch (states set and read per call).
    """

    #: States per ``mujoco.rollout`` call (bounds the memory of its state output).
    ROLLOUT_BLOCK = 2048

    def __init__(self, world: LinkWorld, phi_home: float, threads: int = 1,
                 block: int = 64):
        self.world, self.phi_home, self.block = world, phi_home, block
        m = world.model
        worlds = [LinkWorld(share_model_of=world) for _ in range(block)]
        # The batch only sets states and computes kinematics: short C calls between
        # Python that holds the GIL, so threads there cost more than they gave (measured
        # with the rollout on two threads: a third slower).
        self.batch = WorldBatch(worlds, [[] for _ in worlds], threads=1)
        self.sensor = BatchSensor(self.batch, [IrradianceSensor(w, noise=False)
                                               for w in worlds], steps=0)
        self._datas = [mujoco.MjData(m) for _ in range(threads)]
        self._rollout = rollout.Rollout(nthread=threads if threads > 1 else 0)
        worlds[0].reset()  # the state every transition starts from, but the gimbal's
        self._home = np.empty(mujoco.mj_stateSize(m, FULL))
        mujoco.mj_getState(m, worlds[0].data, self._home, FULL)
        self._iq = 1 + world.ids.hinge_qpos  # state = (time, qpos, qvel, ...)
        self._iv = 1 + m.nq + world.ids.hinge_dof
        self._substeps = world.config.substeps

    def close(self) -> None:
        self.batch.close()
        self._rollout.close()

    def _starts(self, states: np.ndarray) -> np.ndarray:
        x0 = np.tile(self._home, (len(states), 1))
        x0[:, self._iq] = self.phi_home - states[:, 0]
        x0[:, self._iv] = -states[:, 1]
        return x0

    def _padded(self, rows: np.ndarray) -> np.ndarray:
        """``rows`` filled up to ``block`` with copies of its first row."""
        pad = self.block - len(rows)
        return np.concatenate([rows, np.repeat(rows[:1], pad, axis=0)]) if pad else rows

    def f(self, states: np.ndarray, torques: np.ndarray) -> np.ndarray:
        """States (n, 2) [rad, rad/s] one control period later under motor torques
        (n,) [N m] (clipped at the limit, as :meth:`LinkWorld.set_torque` does)."""
        w, m = self.world, self.world.model
        lim = w.config.torque_limit
        out = np.empty_like(states)
        for a in range(0, len(states), self.ROLLOUT_BLOCK):
            part = slice(a, min(a + self.ROLLOUT_BLOCK, len(states)))
            x0 = self._starts(states[part])
            ctrl = np.zeros((len(x0), 1, m.nu))
            ctrl[:, 0, w.ids.motor] = np.clip(torques[part], -lim, lim)
            end = self._rollout.rollout(m, self._datas, x0, ctrl,
                                        nstep=self._substeps)[0][:, -1]
            # An unstable substep makes MuJoCo reset the data (time back to 0).
            if np.any(end[:, 0] < (self._substeps - 0.5) * m.opt.timestep):
                raise WorldError("the physics became unstable in a transition (forces "
                                 "or speeds out of range)")
            out[part, 0] = self.phi_home - end[:, self._iq]
            out[part, 1] = self._per_block(end, self.sensor.incidence_rate0)
        return out

    def _per_block(self, states: np.ndarray, read) -> np.ndarray:
        """``read()`` of the batch set to each block of full physics states (n, nstate),
        concatenated over the blocks."""
        parts = []
        for a in range(0, len(states), self.block):
            rows = states[a:a + self.block]
            self.batch.set_state(self._padded(rows))
            parts.append(read()[:len(rows)])
        return np.concatenate(parts)

    def h(self, states: np.ndarray) -> np.ndarray:
        """Noise-free photodiode powers (n, 2) [W] at the states (n, 2)."""
        # The state a reset gives, set directly: the same kinematics without
        # mj_resetData and mj_forward.
        return self._per_block(self._starts(states), lambda: self.sensor.clean()[0])
