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


def head_rates(o, sight, velocity, transmitter, up, normal):
    """(d(azimuth)/dt, d(elevation)/dt) [rad/s] of a photodiode on a pan-tilt head: the
    line of sight's turn in the photodiode's own frame (normal, up), whose up turns with
    it (exact for a photodiode that looks along its head's boresight, as the data
    detector does).

    The azimuth is :func:`incidence_geometry`'s phi about ``up``, atan2((n x s).u, n.s),
    and the elevation asin(s.u), with s the unit line of sight. Its turn in the frame is
    m = ds/dt - w x s, ds/dt = (r - s (s.r)) / d, r the LED's velocity less the
    photodiode's.

    Args:
        sight: LED - photodiode [m]; velocity: the photodiode's (angular [rad/s],
            linear [m/s]) velocity (``mj_objectVelocity``'s order); transmitter: the
            LED's linear velocity [m/s]; up, normal: the photodiode's unit up and normal
            (:func:`photodiode_up`). Each a triple.
    """
    lx, ly, lz = sight
    wx, wy, wz, vx, vy, vz = velocity
    rx, ry, rz = transmitter[0] - vx, transmitter[1] - vy, transmitter[2] - vz
    ux, uy, uz = up
    nx, ny, nz = normal
    d = o.sqrt(lx * lx + ly * ly + lz * lz)
    sx, sy, sz = lx / d, ly / d, lz / d
    sr = sx * rx + sy * ry + sz * rz
    # m = (r - s (s.r)) / d - w x s
    mx = (rx - sx * sr) / d - (wy * sz - wz * sy)
    my = (ry - sy * sr) / d - (wz * sx - wx * sz)
    mz = (rz - sz * sr) / d - (wx * sy - wy * sx)
    # the azimuth: atan2(a, b) with a = (n x s).u, b = n.s
    a = (ny * sz - nz * sy) * ux + (nz * sx - nx * sz) * uy + (nx * sy - ny * sx) * uz
    da = (ny * mz - nz * my) * ux + (nz * mx - nx * mz) * uy + (nx * my - ny * mx) * uz
    b = nx * sx + ny * sy + nz * sz
    db = nx * mx + ny * my + nz * mz
    azimuth_rate = (da * b - a * db) / (a * a + b * b)
    e = sx * ux + sy * uy + sz * uz  # sin(elevation)
    elevation_rate = (mx * ux + my * uy + mz * uz) / o.sqrt(1.0 - e * e)
    return azimuth_rate, elevation_rate
