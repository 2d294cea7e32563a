"""Wave forces on the hull by strip theory: the hull cut into slices along its axis,
each feeling the water's acceleration and velocity where it is.

On a slice of length dx, radius r and volume dV = pi r^2 dx at a point where the wave's
water moves with velocity u_w and acceleration a_w (:mod:`ledsim.physics.linear_waves`)
the excitation is Morison's, split along the hull's axis e and across it (Prestero
2001, sec. 3; Fossen 2011, ch. 6 and 8)::

    dF = rho dV [(1 + Ca) s a_w,perp + a_w,axial]               Froude-Krylov + diffraction
       + 1/2 rho Cd (2 r dx) (|q| q - |q0| q0)_perp             cross-flow drag
    q  = u_w + u_c - v                                         (u_c: a current, v: the slice's)

with s = m / (m + Ca rho V) (:attr:`HullStrips.across_share`: MuJoCo's bodies have no
added mass, so the force is the one that gives the hull its true acceleration). MuJoCo's
own fluid model (every geom's ellipsoid: hull, fins, gimbal) gives the drag in the
water's velocity at the hull's origin, set as the medium velocity (``opt.wind``, with
any current); the slices add the wave's inertia force (MuJoCo's medium does not
accelerate) and the drag's change from that one velocity to each slice's own (q0 =
u_w(origin) + u_c - v in the formula above). Their sum over the hull, and its moment
about the hull's centre of mass, is a wrench through ``xfrc_applied``. Because u_w and
a_w differ from slice to slice, the wave heaves, surges and pitches the hull (and rolls
it, coming from the side), as it does a real one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from ledsim.physics.linear_waves import RegularWave


@dataclass(frozen=True)
class StripCoefficients:
    """The hull's coefficients for the slices.

    The hull is REMUS-100 class (``led_link.xml``: 1.6 m, 0.19 m across), and so are
    the figures, Prestero's for REMUS-100 (T. Prestero, *Verification of a six-degree of
    freedom simulation model for the REMUS autonomous underwater vehicle*, MIT/WHOI
    2001, tab. 3.1 and sec. 3.2-3.3): his added mass is this strip theory's (Ca = 1 on
    each circular section), his cross-flow drag coefficient Hoerner's for a cylinder.
    The thrusters for sway and heave are those of a hovering torpedo AUV such as
    Delphin2 (Phillips et al., Trans. RINA 2013); no hovering torpedo AUV publishes its
    own coefficients or wave response, so none is claimed.

    Attributes:
        added_mass: Ca, a section's added mass across the axis over its displaced
            water's [-] (1: a circle).
        crossflow_drag: Cd, a section's drag coefficient across the axis, on its
            diameter [-] (0.6: Prestero's, after Hoerner 1965).
        strips: how many slices [-].
    """

    added_mass: float = 1.0
    crossflow_drag: float = 0.6
    strips: int = 12


class HullStrips:
    """The slices of the hull geom ``hull`` (an ellipsoid along its body's x) of
    ``model``; :meth:`wrench` gives the wave's force on them."""

    def __init__(self, model: mujoco.MjModel, coefficients: StripCoefficients | None = None):
        self.coefficients = c = coefficients or StripCoefficients()
        geom = model.geom("hull")
        if model.geom_type[geom.id] != mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            raise ValueError("the hull geom must be an ellipsoid along the body's x axis")
        a, b, _ = (float(v) for v in geom.size)
        self.body = int(geom.bodyid[0])
        self.density = float(model.opt.density)
        self.mass = float(model.body_mass[self.body])
        dx = 2.0 * a / c.strips
        x = -a + dx * (np.arange(c.strips) + 0.5)
        self.radius = b * np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None))
        self.volume = math.pi * self.radius**2 * dx  # [m^3]
        self.width = 2.0 * self.radius * dx  # projected area across the axis [m^2]
        # the slices' centres in the body's frame (the geom's own offset included)
        local = np.zeros((c.strips, 3))
        local[:, 0] = x
        self.local = local + np.asarray(geom.pos, dtype=float)

    @property
    def across_share(self) -> float:
        """m / (m + Ca rho V): MuJoCo's bodies carry no added mass, so the inertia force
        across the hull is scaled to give the acceleration it gives the hull with its
        added mass, (1 + Ca) rho V a / (m + Ca rho V) (the water's own, a, for a neutrally
        buoyant hull)."""
        added = self.coefficients.added_mass * self.density * float(self.volume.sum())
        return self.mass / (self.mass + added)

    def wrench(self, model: mujoco.MjModel, data: mujoco.MjData, wave: RegularWave,
               surface_z: float, t: float, current=(0.0, 0.0, 0.0)
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At time ``t`` [s], the still surface at world z = ``surface_z`` [m], with a
        ``current`` [m/s]: the water's velocity at the body's origin [m/s] (for MuJoCo's
        medium velocity, which every geom's fluid forces then feel), and the slices'
        force [N] and torque about the body's centre of mass [N m], world frame: the
        wave's inertia force, and the drag's change from that one velocity to each
        slice's own."""
        c = self.coefficients
        R = data.xmat[self.body].reshape(3, 3)
        origin = data.xpos[self.body]
        arm = self.local @ R.T
        pos = origin + arm
        vel6 = np.zeros(6)
        # at the body's origin (XBODY), world-aligned: (angular, linear)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_XBODY, self.body, vel6, 0)
        v = vel6[3:] + np.cross(vel6[:3], arm)
        u_w, a_w = wave.kinematics(pos, surface_z - pos[:, 2], t)
        u_c, _ = wave.kinematics(origin, surface_z - origin[2], t)
        e = R[:, 0]
        rho = self.density
        a_axial = (a_w @ e)[:, None] * e
        across = (1.0 + c.added_mass) * self.across_share
        force = rho * self.volume[:, None] * (across * (a_w - a_axial) + a_axial)
        q = u_w + np.asarray(current) - v  # the water past each slice
        q0 = q - u_w + u_c  # what MuJoCo's model sees there (the origin's wave velocity)
        q = q - (q @ e)[:, None] * e
        q0 = q0 - (q0 @ e)[:, None] * e
        drag = np.linalg.norm(q, axis=1)[:, None] * q - np.linalg.norm(q0, axis=1)[:, None] * q0
        force = force + 0.5 * rho * c.crossflow_drag * self.width[:, None] * drag
        lever = pos - data.xipos[self.body]
        return u_c, force.sum(axis=0), np.cross(lever, force).sum(axis=0)
