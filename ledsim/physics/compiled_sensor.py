"""The ray sensor's reading (:meth:`~ledsim.physics.sensor.IrradianceSensor.read`),
compiled: two kernels around MuJoCo's ray casts, to the reference's last bit.

The reference reads each photodiode's pose, line of sight, rays and powers in plain
floats, a few hundred Python operations a photodiode. Here :func:`geometry` takes
MuJoCo's pose arrays as they are and gives every photodiode's (d, theta, phi), its rays
and (on a tilted head) its up and elevation; ``mj_multiRay`` casts each photodiode's
rays; :func:`powers` counts the rays that got through and forms the powers.

Each kernel does the reference's operations in its order with libm's functions, as
Python's floats do (numba calls libm for ``atan2``, ``acos``, ``asin``, ``exp``,
``cos`` and ``pow`` and does not contract a * b + c): the reading has the reference's
bits, so a world reads the same alone or with others (:mod:`ledsim.physics.sensor_rows`),
tested. Two details keep them: Python's ``min``/``max`` (which keep the first argument
unless the second is strictly beyond it) are written out, and x**2 is libm's
``pow(x, 2)`` with the 2 passed at run time (LLVM would fold a constant 2 into x * x,
which differs from libm's pow in the last bit for about 1 value in 1300).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from observer.jit import njit

#: The optics' constants in :func:`powers`' order (``optics`` of :func:`constants`).
_OPTICS = ("power_scale", "attenuation", "lambertian_order")
_RESPONSE = ("a1", "b1", "c1", "a2", "b2", "c2")


def constants(c) -> np.ndarray:
    """The link's optics (``LinkConstants`` ``c``) as :func:`powers` takes them: a,
    b, the Lambertian order, the receiver's a1, b1, c1, a2, b2, c2, and 2.0 (the
    square's exponent, at run time)."""
    return np.array([float(getattr(c, k)) for k in _OPTICS]
                    + [float(getattr(c.receiver, k)) for k in _RESPONSE] + [2.0])


@njit()
def _min(a: float, b: float) -> float:  # Python's min(a, b)
    return b if b < a else a


@njit()
def _max(a: float, b: float) -> float:  # Python's max(a, b)
    return b if b > a else a


@njit()
def geometry(site_xpos, site_xmat, xmat, sites, led, gimbal, tilted, targets, d, theta,
             phi, up, dirs, lengths, reach, elevation) -> None:
    """Each photodiode's (d [m], theta, phi [rad]) into ``d``, ``theta``, ``phi`` (n,),
    its up into ``up`` (n, 3), the unit directions of its rays to ``targets`` (R, 3)
    (the aperture's points [m]) into ``dirs`` (n, 3 R), their lengths [m] into
    ``lengths`` (n, R) and their longest into ``reach`` (n,), and its elevation [rad]
    out of the plane normal to its up into ``elevation`` (n,); MuJoCo's ``site_xpos``, ``site_xmat``
    and ``xmat`` as they are, with the photodiodes' ``sites``, the LED's site and the
    gimbal's body."""
    lx, ly, lz = site_xpos[led, 0], site_xpos[led, 1], site_xpos[led, 2]
    ax, ay, az = site_xmat[led, 2], site_xmat[led, 5], site_xmat[led, 8]
    hx, hy, hz = xmat[gimbal, 2], xmat[gimbal, 5], xmat[gimbal, 8]
    for i in range(sites.size):
        s = sites[i]
        px, py, pz = site_xpos[s, 0], site_xpos[s, 1], site_xpos[s, 2]
        nx, ny, nz = site_xmat[s, 2], site_xmat[s, 5], site_xmat[s, 8]
        ux, uy, uz = hx, hy, hz
        if tilted:  # incidence.photodiode_up
            k = hx * nx + hy * ny + hz * nz
            ux, uy, uz = hx - k * nx, hy - k * ny, hz - k * nz
            m = math.sqrt(ux * ux + uy * uy + uz * uz)
            ux, uy, uz = ux / m, uy / m, uz / m
        up[i, 0], up[i, 1], up[i, 2] = ux, uy, uz
        # incidence.incidence_geometry, about the up
        vx, vy, vz = lx - px, ly - py, lz - pz
        dist = math.sqrt(vx * vx + vy * vy + vz * vz)
        vx, vy, vz = vx / dist, vy / dist, vz / dist
        cross_h = (ny * vz - nz * vy) * ux + (nz * vx - nx * vz) * uy + \
            (nx * vy - ny * vx) * uz
        d[i] = dist
        phi[i] = math.atan2(cross_h, nx * vx + ny * vy + nz * vz)
        theta[i] = math.acos(_max(-1.0, _min(1.0, -(ax * vx + ay * vy + az * vz))))
        # sensor._tilted_elevation (on a head that does not tilt, out of the hinge's
        # plane as the head's truth reads it; sensor.elevation reads that otherwise)
        vx, vy, vz = lx - px, ly - py, lz - pz
        sine = (vx * ux + vy * uy + vz * uz) / math.sqrt(vx * vx + vy * vy + vz * vz)
        elevation[i] = math.asin(_max(-1.0, _min(1.0, sine)))
        longest = 0.0
        for r in range(targets.shape[0]):  # sensor.visible_fraction's rays
            vx, vy, vz = targets[r, 0] - px, targets[r, 1] - py, targets[r, 2] - pz
            n = math.sqrt(vx * vx + vy * vy + vz * vz)
            dirs[i, 3 * r], dirs[i, 3 * r + 1], dirs[i, 3 * r + 2] = vx / n, vy / n, vz / n
            lengths[i, r] = n
            longest = n if r == 0 else _max(longest, n)
        reach[i] = longest


@njit()
def _response(phi: float, c: np.ndarray) -> float:
    """optics.receiver_response_at in floats."""
    u1, u2 = (phi - c[4]) / c[5], (phi + c[7]) / c[8]
    return c[3] * math.exp(-(u1 * u1)) + c[6] * math.exp(-(u2 * u2))


@njit()
def powers(d, theta, phi, hits, lengths, elevation, cone, c, vis, clean) -> None:
    """Each photodiode's visible fraction into ``vis`` (the share of its rays that no
    geom stopped short of its length: ``hits`` (n, R) ``mj_multiRay``'s distances, -1
    where nothing was hit) and its clean power [W] into ``clean``: vis x a exp(-b d) /
    d^2 x I~(theta) x g(phi), times g(elevation) where ``cone`` (a physical receiver's
    field of view); ``c`` from :func:`constants`."""
    for i in range(d.size):
        blocked = 0
        for r in range(hits.shape[1]):
            if 0.0 <= hits[i, r] < lengths[i, r]:
                blocked += 1
        vis[i] = 1.0 - blocked / hits.shape[1]
        cos_t = _max(math.cos(theta[i]), 0.0)
        gain = c[0] * math.exp(-c[1] * d[i]) / math.pow(d[i], c[9]) * math.pow(cos_t, c[2])
        clean[i] = vis[i] * gain * _response(phi[i], c)
        if cone:
            clean[i] = clean[i] * _response(elevation[i], c)


class Reader:
    """The buffers and constants of one sensor's compiled reading."""

    def __init__(self, sensor):
        w = sensor.world
        n, rays = sensor.layout.n_photodiodes, len(sensor._aperture)
        ids = w.ids
        self.sites = np.array(ids.photodiode_sites[:n], dtype=np.int64)
        self.led, self.gimbal = int(ids.led_site), int(ids.gimbal_body)
        self.tilted = bool(sensor._tilted)
        self.optics = constants(sensor.constants)
        self.d, self.theta, self.phi, self.reach, self.elevation, self.vis, self.clean = \
            (np.zeros(n) for _ in range(7))
        self.up, self.dirs = np.zeros((n, 3)), np.zeros((n, 3 * rays))
        self.lengths, self.hits = np.zeros((n, rays)), np.zeros((n, rays))
        self.geom = np.zeros(rays, dtype=np.int32)

    def read(self, sensor, cone: bool) -> None:
        """The sensor's geometry, rays and clean powers (before the light and the
        channels' gains) into this reader's buffers. ``cone``: times the elevation's
        response (at :attr:`elevation` on a tilted head, else at the sensor's
        :meth:`~ledsim.physics.sensor.IrradianceSensor.elevation`)."""
        from ledsim.physics.world import RAY_GROUPS

        w = sensor.world
        m, data = w.model, w.data
        geometry(data.site_xpos, data.site_xmat, data.xmat, self.sites, self.led,
                 self.gimbal, self.tilted, sensor.aperture_points(), self.d, self.theta,
                 self.phi, self.up, self.dirs, self.lengths, self.reach, self.elevation)
        rays, reach = self.geom.size, self.reach.tolist()
        for i, site in enumerate(self.sites.tolist()):
            mujoco.mj_multiRay(m, data, data.site_xpos[site], self.dirs[i], RAY_GROUPS, 1,
                               self.gimbal, self.geom, self.hits[i], None, rays, reach[i])
        cone_elevation = self.elevation if self.tilted or not cone else sensor.elevation()
        powers(self.d, self.theta, self.phi, self.hits, self.lengths, cone_elevation, cone,
               self.optics, self.vis, self.clean)
