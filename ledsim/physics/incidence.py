"""A photodiode's line of sight to the LED, as row kernels: one world in plain floats,
or N worlds in arrays with the same operations element by element.

Each kernel takes its vectors as triples of components (floats for one world, (N,)
arrays for N) and the arithmetic ``o`` of :mod:`observer.rowops` where it needs more than
IEEE's + - * / (``atan2`` and ``acos`` are libm's on both sides), so a world's reading
has the same bits read alone (:class:`~ledsim.physics.sensor.IrradianceSensor`) or with
others (:class:`~ledsim.physics.sensor_rows.SensorRows`).
"""

from __future__ import annotations


def incidence_geometry(o, led, axis, hinge, photodiode, normal):
    """(d [m], theta [rad], phi [rad]) of one photodiode:

        d     = |LED - photodiode|
        theta = angle(LED axis, photodiode - LED)
        phi   = signed angle(photodiode normal, LED - photodiode), about the hinge

    from the LED's position [m] and unit axis, the hinge's unit axis, and the
    photodiode's position [m] and unit normal (each a triple)."""
    lx, ly, lz = led
    ax, ay, az = axis
    hx, hy, hz = hinge
    px, py, pz = photodiode
    nx, ny, nz = normal
    vx, vy, vz = lx - px, ly - py, lz - pz
    d = o.sqrt(vx * vx + vy * vy + vz * vz)
    vx, vy, vz = vx / d, vy / d, vz / d
    cross_h = (ny * vz - nz * vy) * hx + (nz * vx - nx * vz) * hy + \
        (nx * vy - ny * vx) * hz
    phi = o.atan2(cross_h, nx * vx + ny * vy + nz * vz)
    theta = o.acos(o.maximum(-1.0, o.minimum(1.0, -(ax * vx + ay * vy + az * vz))))
    return d, theta, phi


def photodiode_up(o, normal, hinge):
    """The unit "up" of a photodiode on a tilting head: the pan hinge's axis less its
    part along the photodiode's normal. The photodiode's azimuth is about it
    (:func:`incidence_geometry` with it as the hinge) and its elevation is the line of
    sight's angle out of the plane normal to it. On a head that only pans, the normals
    lie in the turning plane and it is the hinge axis itself (which the one-axis paths
    pass as it is, to the last bit)."""
    nx, ny, nz = normal
    hx, hy, hz = hinge
    k = hx * nx + hy * ny + hz * nz
    ux, uy, uz = hx - k * nx, hy - k * ny, hz - k * nz
    m = o.sqrt(ux * ux + uy * uy + uz * uz)
    return ux / m, uy / m, uz / m


def incidence_rate(sight, velocity, transmitter, hinge):
    """d(phi)/dt [rad/s] of a photodiode: the line of sight's rotation minus the
    photodiode's, about the hinge axis (exact for rotations about that axis).

    Args:
        sight: LED - photodiode [m] (a triple).
        velocity: the photodiode's (angular [rad/s], linear [m/s]) velocity, six
            components (``mj_objectVelocity``'s order).
        transmitter: the LED's linear velocity [m/s] (a triple).
        hinge: the hinge's unit axis (a triple).
    """
    lx, ly, lz = sight
    wx, wy, wz, vx, vy, vz = velocity
    tx, ty, tz = transmitter
    hx, hy, hz = hinge
    rx, ry, rz = tx - vx, ty - vy, tz - vz
    d2 = lx * lx + ly * ly + lz * lz
    los_rate = ((ly * rz - lz * ry) * hx + (lz * rx - lx * rz) * hy
                + (lx * ry - ly * rx) * hz) / d2
    return los_rate - (wx * hx + wy * hy + wz * hz)
