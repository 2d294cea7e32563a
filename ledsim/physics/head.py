"""The receiver head in the MJCF, built from its layout (:mod:`ledsim.physics.layout`):
each photodiode's normal, and the gimbal axes the scene lacks.

The shipped scene has one axis: the pan hinge ``gimbal_hinge`` of body ``gimbal``, its
motor and its encoder, and the paper's pair of photodiodes on it. A second axis of a
layout (tilt, in elevation) that the scene does not have is built here through
``mujoco.MjSpec``: a body inside the gimbal turning about the axis's ``direction`` on a
hinge with the pan hinge's damping and armature, a motor (MuJoCo's ``motor`` actuator on
the joint) and an encoder (a ``jointpos`` sensor), and the layout's photodiode sites on
it, spread on a ring on the head's face. The torque limit is applied to every axis's
motor by the scene.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ledsim.errors import LedsimError
from ledsim.physics.layout import ReceiverLayout

#: Radius of the ring a built axis's photodiodes sit on, on the head's face [m].
RING_RADIUS = 0.003
#: Mass [kg] and moment of inertia [kg m^2] of a built axis's head.
HEAD_MASS, HEAD_INERTIA = 0.005, 2e-7


def photodiode_normal(offset: float, tilt: float) -> list[float]:
    """The normal of a photodiode whose incidence angle is the reference's plus
    ``offset`` about the pan axis (z) and whose elevation is the reference's plus
    ``tilt`` [rad]: the reference normal +x turned down by ``tilt`` (about y), then by
    ``-offset`` about z. Both angles are the line of sight's in the photodiode's view,
    positive to the left and up: a normal turned right (or down) sees the LED that much
    further left (or up)."""
    x, z = math.cos(tilt), -math.sin(tilt)
    c, s = math.cos(-offset), math.sin(-offset)
    return [c * x, s * x, z]


def set_zaxis(element, direction) -> None:
    """Orient an MjSpec site/geom so its z axis is ``direction`` (overrides the XML's)."""
    element.alt.type = mujoco.mjtOrientation.mjORIENTATION_ZAXIS
    element.alt.zaxis = list(direction)


def add_motor(spec: mujoco.MjSpec, name: str, joint: str) -> None:
    """A torque motor on ``joint`` (its range is the scene's torque limit)."""
    spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT,
                      gear=[1, 0, 0, 0, 0, 0])


def check_hinges(spec: mujoco.MjSpec, layout: ReceiverLayout,
                 error: type[LedsimError]) -> None:
    """A scene's hinges fit the layout: each of its axes the scene has is a hinge about
    the axis's direction, and the gimbal carries no joint the layout does not turn (a
    ``--scene`` with a tilt hinge under the yaw gimbal, or a pan hinge about x)."""
    names = [a.name for a in layout.axes]
    for axis in layout.axes:
        joint = spec.joint(axis.joint)
        if joint is None:
            continue
        if joint.type != mujoco.mjtJoint.mjJNT_HINGE:
            raise error(f"the scene's joint {axis.joint!r} is a "
                        f"{joint.type.name.removeprefix('mjJNT_').lower()} joint: the "
                        f"{axis.name} axis needs a hinge")
        turn = np.asarray(joint.axis, float)
        if not np.allclose(turn / np.linalg.norm(turn), axis.direction, atol=1e-6):
            raise error(f"the scene's hinge {axis.joint!r} turns about "
                        f"{tuple(float(v) for v in turn)}, not the {axis.name} axis's "
                        f"{tuple(axis.direction)}")
    joints = {a.joint for a in layout.axes}
    for joint in spec.body("gimbal").find_all(mujoco.mjtObj.mjOBJ_JOINT):
        if joint.name not in joints:
            raise error(f"the scene's gimbal has a joint {joint.name!r} that a head of "
                        f"axes {', '.join(names)} does not turn (--gimbal pan-tilt turns "
                        "'gimbal_hinge' and 'tilt_hinge'; --gimbal yaw 'gimbal_hinge')")


def build_head(spec: mujoco.MjSpec, layout: ReceiverLayout, damping: float,
               error: type[LedsimError]) -> list:
    """Turn each photodiode's normal to its offsets, and build the axes the scene lacks
    (see the module's text); returns the photodiodes' sites, in the layout's order."""
    body = spec.body("gimbal")
    if spec.joint(layout.axes[0].joint) is None:
        raise error(f"the scene has no joint named {layout.axes[0].joint!r} for the "
                    f"first axis ({layout.axes[0].name})")
    check_hinges(spec, layout, error)
    first_hinge = spec.joint(layout.axes[0].joint)
    for axis in layout.axes[1:]:
        if spec.joint(axis.joint) is not None:
            continue
        for kind, name in (("body", axis.name), ("actuator", axis.motor),
                           ("sensor", axis.encoder)):
            if getattr(spec, kind)(name) is not None:
                raise error(f"the scene already has a {kind} named {name!r}: axis "
                            f"{axis.name!r} cannot be built there")
        body = body.add_body(name=axis.name, pos=[0.0, 0.0, 0.0], mass=HEAD_MASS,
                             inertia=[HEAD_INERTIA] * 3, explicitinertial=True)
        body.add_joint(name=axis.joint, type=mujoco.mjtJoint.mjJNT_HINGE,
                       axis=list(axis.direction), damping=[damping, 0.0, 0.0],
                       armature=first_hinge.armature)
        add_motor(spec, axis.motor, axis.joint)
        spec.add_sensor(name=axis.encoder, type=mujoco.mjtSensor.mjSENS_JOINTPOS,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=axis.joint)
    built = body.name != "gimbal"
    sites = []
    for k, p in enumerate(layout.photodiodes):
        site = spec.site(p.site)
        if built:
            if site is not None:
                raise error(f"photodiode site {p.site!r} is on the scene's pan axis: a "
                            "layout with a built tilt axis names sites of its own")
            a = 2.0 * math.pi * k / layout.n_photodiodes
            site = body.add_site(name=p.site, size=[0.0025, 0, 0], pos=[
                0.0, RING_RADIUS * math.cos(a), RING_RADIUS * math.sin(a)])
        elif site is None:
            raise error(f"the scene has no site named {p.site!r}")
        sites.append(site)
        # The reference photodiode keeps the scene's own normal (paper eq. eq-4a: the
        # second's is turned by -dphi about the hinge).
        if p.offset == 0.0 and p.tilt == 0.0 and not built:
            continue
        normal = photodiode_normal(p.offset, p.tilt)
        set_zaxis(site, normal)
        lens = spec.geom(f"{p.site}_lens")
        if lens is not None:
            set_zaxis(lens, normal)
    return sites


def receiver_centre(sites: list) -> np.ndarray:
    """The receiver's centre in the gimbal's frame [m]: the photodiodes' midpoint."""
    return np.mean([np.asarray(site.pos) for site in sites], axis=0)


#: The least pan gain the agent divides by [-]: within 84 deg of the pole the pan
#: swings at most ten times the azimuth it turns.
MIN_PAN_GAIN = 0.1


def pan_gain(tilt: float) -> float:
    """How much of the pan's turn the line of sight's azimuth takes at encoder tilt
    ``tilt`` [rad] (0: the boresight level) [-]: cos(tilt), at least
    :data:`MIN_PAN_GAIN`."""
    return max(abs(math.cos(tilt)), MIN_PAN_GAIN)


def to_encoder(angles, q) -> np.ndarray:
    """The encoder offsets [rad] that turn the head by the head-frame ``angles`` [rad]
    (azimuth, elevation), at encoder angles ``q`` [rad]."""
    return np.array([angles[0] / pan_gain(q[1]), angles[1]])


def to_head(offsets, q) -> np.ndarray:
    """The head-frame angles [rad] an encoder turn of ``offsets`` [rad] gives at ``q``."""
    return np.array([offsets[0] * pan_gain(q[1]), offsets[1]])
