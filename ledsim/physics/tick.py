"""The physics tick: the one way the world moves from one control step to the next.

Every world starts a step through :func:`prepare` and moves through the same three
parts, so a control step sees the same world whoever runs it. The rows of
:class:`~ledsim.physics.world_rows.WorldRows` (the closed loop, the envs, ``simulate``,
the wave response) and the training data's ``WorldBatch`` take them for many worlds at
once (:func:`step_worlds`); :func:`advance` is the same tick for one world, in one call:

    prepare(t):   hull wrench cleared, disturbances act at t, kinematics updated, the
                  vehicle (if any) senses, navigates and sets its thrusters
    (the sensor reads, the controller picks a torque)
    advance:      torque commanded (clipped at the limit), physics steps Te,
                  prepare(t + Te)

Many worlds (the runs of several seeds, a vector of environments) take the same three
parts in turn: every torque commanded, every world's physics stepped in one pass
(:class:`PhysicsPass`, split over threads: MuJoCo steps without the GIL), every world
prepared. A world's numbers do not depend on the others beside it.
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

from ledsim.physics.world import LinkWorld


def prepare(world: LinkWorld, disturbances: Sequence, t: float, vehicle=None) -> None:
    """Start control step ``t`` [s]: the disturbances act, then the kinematics, then the
    vehicle (:class:`~ledsim.agent.autopilot.Vehicle`, or None) acts."""
    world.clear_hull_wrench()
    for d in disturbances:
        d.apply(world, t)
    world.forward_kinematics()
    if vehicle is not None:
        vehicle.act(t)


def advance(world: LinkWorld, disturbances: Sequence, torque: float, t_next: float,
            vehicle=None) -> float:
    """Command ``torque`` [N m], step the physics one control period and prepare step
    ``t_next`` [s]. Returns the torque applied (after the motor's limit) [N m]."""
    applied = world.set_torque(torque)
    world.step()
    prepare(world, disturbances, t_next, vehicle)
    return applied


def step_worlds(physics: PhysicsPass, worlds: Sequence[tuple[LinkWorld, Sequence, float]],
                vehicles=None, vehicle_time=None) -> None:
    """The rest of the tick of many worlds, once each one's torque is commanded: the
    physics of ``worlds`` (``(world, disturbances, t_next)`` each) in one pass of
    ``physics``, each world prepared at its ``t_next`` [s], then the stacked
    ``vehicles`` (:class:`~ledsim.agent.autopilot.Vehicle`, or None) in one pass at
    ``vehicle_time`` [s] (one time, or one per row)."""
    physics([w for w, _, _ in worlds])
    for world, disturbances, t_next in worlds:
        prepare(world, disturbances, t_next)
    if vehicles is not None:
        vehicles.act_rows(vehicle_time)


class OwnsThreads:
    """A context manager that owns a thread pool (``_pool``, None for one thread) and
    shuts it down on :meth:`close`."""

    _pool: ThreadPoolExecutor | None = None

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class PhysicsPass(OwnsThreads):
    """Step the physics of many worlds one control period each, split over ``threads``
    (1: in the calling thread). A context manager: it owns its threads.

    Args:
        worlds: the worlds, in a fixed order.
        threads: threads stepping them (at most one per world).
    """

    def __init__(self, worlds: Sequence[LinkWorld], threads: int = 1):
        self.worlds = list(worlds)
        self.threads = max(1, min(int(threads), len(self.worlds)))
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None

    @staticmethod
    def _step(worlds: Sequence[LinkWorld]) -> None:
        for w in worlds:
            w.step()

    def __call__(self, worlds: Sequence[LinkWorld] | None = None) -> None:
        """One control period of every world's physics (torques already commanded), or
        of ``worlds`` only."""
        worlds = self.worlds if worlds is None else worlds
        if self._pool is None:
            self._step(worlds)
            return
        chunks = [worlds[i::self.threads] for i in range(self.threads)]
        for f in [self._pool.submit(self._step, c) for c in chunks]:
            f.result()
