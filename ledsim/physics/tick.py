"""The physics tick: the one way the world moves from one control step to the next.

``simulate``, the closed loop (one run or many), the training data and the Gymnasium
environment all advance the world through :func:`advance`, and start a step through
:func:`prepare`, so a control step sees the same world whoever runs it:

    prepare(t):   hull wrench cleared, disturbances act at t, kinematics updated, the
                  vehicle (if any) senses, navigates and sets its thrusters
    (the sensor reads, the controller picks a torque)
    advance:      torque commanded (clipped at the limit), physics steps Te,
                  prepare(t + Te)
"""

from __future__ import annotations

from collections.abc import Sequence

from .world import LinkWorld


def prepare(world: LinkWorld, disturbances: Sequence, t: float, vehicle=None) -> None:
    """Start control step ``t`` [s]: the disturbances act, then the kinematics, then the
    vehicle (:class:`~ledsim.physics.vehicle.Vehicle`, or None) acts."""
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
