"""N copies of the world stepped together, and their poses as arrays.

:class:`WorldPoses` gathers what the sensors read from N worlds' ``MjData`` into (N, ...)
arrays, whoever steps them (the closed loop's :class:`~ledsim.physics.tick.PhysicsPass`,
or a batch). :class:`WorldBatch` holds one :class:`LinkWorld` per run, each with its
own ``MjData`` (and one shared ``MjModel`` unless a disturbance changes the model: a
water current sets its medium velocity). One control period of every world is a single
call: set the motor torques, ``mj_step`` through the substeps, apply each world's
disturbances for the next step and update its kinematics. MuJoCo releases the GIL while
it steps, so the worlds are split over ``threads`` threads. The poses the sensor needs
(:mod:`ledsim.physics.batch_sensor`) are then stacked into (N, ...) arrays.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from ledsim.physics.tick import PhysicsPass, prepare, step_worlds
from ledsim.physics.world import RAY_GROUPS, LinkWorld


class WorldPoses:
    """The poses N worlds' sensors read, as (N, ...) arrays: :meth:`gather` copies them
    from every world's ``MjData`` (one concatenate per quantity: cheaper than N row
    copies), whoever steps the worlds.

    Args:
        worlds: the worlds (one model layout: the same sites, bodies and geoms).
    """

    def __init__(self, worlds: Sequence[LinkWorld]):
        if not worlds:
            raise ValueError("at least one world")
        self.worlds = list(worlds)
        n = len(self.worlds)
        w0 = self.worlds[0]
        m = w0.model
        ids = w0.ids
        self._sites = np.array([*ids.photodiode_sites, ids.led_site])
        #: Photodiodes of the receiver (its layout's order), and the reference one's index.
        self.n_photodiodes = len(ids.photodiode_sites)
        self.reference = w0.config.constants.layout.reference
        self._gimbal = ids.gimbal_body
        self._root = int(m.body_rootid[ids.gimbal_body])
        # Geoms that block light (groups 0-2, not the gimbal): planes, and the others
        # with their bounding radius (none: no bound, so rays always).
        blocking = (m.geom_group < 3) & (m.geom_bodyid != ids.gimbal_body) & \
            (RAY_GROUPS[np.minimum(m.geom_group, 5)] > 0)
        plane = m.geom_type == mujoco.mjtGeom.mjGEOM_PLANE
        self.planes = np.flatnonzero(blocking & plane)
        self.blocking_geoms = np.flatnonzero(blocking & ~plane)
        self.rbound = m.geom_rbound[self.blocking_geoms].copy()
        self.unbounded = bool(np.any(self.rbound <= 0))
        self._all_sites = m.nsite == len(self._sites) and \
            list(self._sites) == list(range(m.nsite))
        self.site_pos = np.empty((n, len(self._sites), 3))  # the photodiodes, the LED
        self.site_mat = np.empty((n, len(self._sites), 9))
        self.gimbal_mat = np.empty((n, 9))
        self.gimbal_cvel = np.empty((n, 6))
        self.root_com = np.empty((n, 3))
        self._qpos_hinge = np.empty((n, 1))
        self._qvel_hinge = np.empty((n, 1))
        self.hull_pos = np.empty((n, 3))
        self.geom_xpos = np.empty((n, m.ngeom, 3))
        self._plane_mat = np.empty((self.planes.size, n, 9))
        self.transmitter_velocity = np.empty((n, 3))
        # Each output as a flat run of its worlds' rows, so that one C-level concatenate
        # fills it (np.stack's Python bookkeeping cost 10 us per world-step).
        self._gathers = [(out.reshape((-1,) + out.shape[2:]), views)
                         for out, views in self._gather_plan()]

    def _gather_plan(self) -> list[tuple[np.ndarray, list]]:
        """(output array, one view per world) of every quantity read each step."""
        ws = self.worlds
        ds = [w.data for w in ws]
        if self._all_sites:
            sites = [(self.site_pos, [d.site_xpos for d in ds]),
                     (self.site_mat, [d.site_xmat for d in ds])]
        else:
            n, ns = len(ws), ws[0].model.nsite
            self._site_xpos_all = np.empty((n, ns, 3))
            self._site_xmat_all = np.empty((n, ns, 9))
            sites = [(self._site_xpos_all, [d.site_xpos for d in ds]),
                     (self._site_xmat_all, [d.site_xmat for d in ds])]
        g, r = self._gimbal, self._root
        return sites + [
            (self.gimbal_mat, [d.xmat[g] for d in ds]),
            (self.gimbal_cvel, [d.cvel[g] for d in ds]),
            (self.root_com, [d.subtree_com[r] for d in ds]),
            (self._qpos_hinge, [d.qpos[w.ids.hinge_qpos:w.ids.hinge_qpos + 1]
                                for w, d in zip(ws, ds, strict=True)]),
            (self._qvel_hinge, [d.qvel[w.ids.hinge_dof:w.ids.hinge_dof + 1]
                                for w, d in zip(ws, ds, strict=True)]),
            (self.hull_pos, [d.xpos[w.ids.hull_body] for w, d in zip(ws, ds, strict=True)]),
            (self.geom_xpos, [d.geom_xpos for d in ds]),
            (self.transmitter_velocity, [w.transmitter_velocity for w in ws])] + [
            (self._plane_mat[j], [d.geom_xmat[p] for d in ds])
            for j, p in enumerate(self.planes.tolist())]

    @property
    def qpos_hinge(self) -> np.ndarray:
        """Gimbal hinge angle of each world [rad], (N,)."""
        return self._qpos_hinge[:, 0]

    @property
    def qvel_hinge(self) -> np.ndarray:
        """Gimbal hinge rate of each world [rad/s], (N,)."""
        return self._qvel_hinge[:, 0]

    def gather(self) -> None:
        """Copy every world's poses into the (N, ...) arrays (one concatenate per
        quantity: cheaper than N row copies)."""
        for out, views in self._gathers:
            np.concatenate(views, out=out)
        if not self._all_sites:
            self.site_pos = self._site_xpos_all[:, self._sites]
            self.site_mat = self._site_xmat_all[:, self._sites]

    @property
    def hinge_axis(self) -> np.ndarray:
        """The gimbal's rotation axis in each world, (N, 3)."""
        return self.gimbal_mat[:, 2::3]

    @property
    def geom_pos(self) -> np.ndarray:
        """Centres of the light-blocking geoms other than planes, (N, G, 3) [m]."""
        return self.geom_xpos[:, self.blocking_geoms]

    @property
    def plane_pos(self) -> np.ndarray:
        """Points of the light-blocking planes, (N, P, 3) [m]."""
        return self.geom_xpos[:, self.planes]

    @property
    def plane_normal(self) -> np.ndarray:
        """Unit normals of the light-blocking planes, (N, P, 3)."""
        return self._plane_mat[:, :, 2::3].transpose(1, 0, 2)

    @property
    def photodiode_normal(self) -> np.ndarray:
        """Unit normals of the photodiodes, (N, n_pd, 3)."""
        return self.site_mat[:, :self.n_photodiodes, 2::3]

    @property
    def photodiode_pos(self) -> np.ndarray:
        """Positions of the photodiodes [m], (N, n_pd, 3)."""
        return self.site_pos[:, :self.n_photodiodes]

    @property
    def led_pos(self) -> np.ndarray:
        """Position of the LED [m], (N, 3)."""
        return self.site_pos[:, self.n_photodiodes]

    @property
    def led_axis(self) -> np.ndarray:
        """The LED's axis (its site's z), (N, 3)."""
        return self.site_mat[:, self.n_photodiodes, 2::3]

    def photodiode_velocity0(self) -> tuple[np.ndarray, np.ndarray]:
        """(angular, linear) velocity of the reference photodiode, each (N, 3), as
        ``mj_objectVelocity`` computes it (the body's com-based velocity moved to the
        site)."""
        ang, lin = self.gimbal_cvel[:, :3], self.gimbal_cvel[:, 3:]
        return ang, lin - cross3(self.site_pos[:, self.reference] - self.root_com, ang)


class WorldBatch(WorldPoses):
    """N worlds advanced one control period at a time (their poses gathered after each):
    the training data's worlds, ticked as :class:`~ledsim.physics.world_rows.WorldRows`
    ticks its rows (:func:`~ledsim.physics.tick.step_worlds` over a
    :class:`~ledsim.physics.tick.PhysicsPass`), without sensors or vehicles. A context
    manager: it owns its threads.

    Args:
        worlds: the worlds, each already reset to its initial state.
        disturbances: per world, its (already reset) disturbances.
        threads: threads that step the worlds (1: in the calling thread).
    """

    def __init__(self, worlds: Sequence[LinkWorld], disturbances: Sequence[Sequence],
                 threads: int = 1):
        if len(worlds) != len(disturbances) or not worlds:
            raise ValueError("one list of disturbances per world, and at least one world")
        super().__init__(worlds)
        n = len(self.worlds)
        self.threads = max(1, min(int(threads), n))
        self._physics = PhysicsPass(self.worlds, self.threads)
        self.disturbances = [list(d) for d in disturbances]
        self.applied = np.zeros(n)  # motor torques of the last step [N m]
        self.time = self.worlds[0].time
        for i in range(n):
            prepare(self.worlds[i], self.disturbances[i], self.time)
        self.gather()

    def step(self, torques: np.ndarray, t_next: float) -> None:
        """Command the motor torques [N m] (clipped at the limit; ``applied`` holds what
        was applied), advance every world by Te, and prepare step ``t_next`` [s]."""
        for i, torque in enumerate(np.asarray(torques, dtype=float).tolist()):
            self.applied[i] = self.worlds[i].set_torque(torque)
        step_worlds(self._physics, list(zip(self.worlds, self.disturbances,
                                            [t_next] * len(self.worlds), strict=True)))
        self.gather()
        self.time = t_next

    def set_state(self, states: np.ndarray) -> None:
        """Every world to its full physics state (``mjSTATE_FULLPHYSICS``, (N, nstate),
        as ``mujoco.rollout`` returns them), with its kinematics."""
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        for i, w in enumerate(self.worlds):
            mujoco.mj_setState(w.model, w.data, states[i], spec)
            prepare(w, self.disturbances[i], float(states[i, 0]))
        self.gather()
        self.time = float(states[0, 0])

    def close(self) -> None:
        self._physics.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Sum over the last axis of 3, in the order of the plain-float code (x, y, z)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis of 3 (MuJoCo's ``mju_cross`` order)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out
