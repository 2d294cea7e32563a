"""What a vehicle's step derives from its reading and its navigation, in the hull's
frame: the bias-corrected rates, the mean acceleration over the step, the velocity, the
gimbal hinge's velocity, and the LED's bearing by the navigated pose. The numpy
reference of every vehicle's (``rows``) or one's (plain floats for the bearing), and the
compiled twin (:mod:`ledsim.agent.compiled_vehicle`) when :func:`observer.jit.enabled`."""

from __future__ import annotations

import math

import numpy as np

from ledsim.physics.batch import cross3
from ledsim.physics.nav_sensors import GRAVITY_REACTION
from observer import jit
from observer.navigation.ins import InsState
from observer.rowops import columns, ops
from observer.rows import matvec as _mv
from observer.rows import transposed as _T

compiled_vehicle = jit.lazy("ledsim.agent.compiled_vehicle")


def hull_frame(r, nav: InsState, vehicle) -> tuple:
    """(omega [rad/s], a [m/s^2], velocity [m/s], the hinge's velocity [m/s], each
    (N, 3) in the hull's frame; the LED's navigated bearing since the start [rad], (N,))
    of ``vehicle``'s rows, from their reading ``r`` and navigation ``nav``."""
    v = vehicle
    if jit.enabled():
        b = compiled_vehicle.body(r.gyro, nav.gyro_bias, nav.attitude, r.delta_velocity,
                                  nav.accel_bias, nav.velocity, nav.position, v.l_gimbal,
                                  v.led, v._bearing0, v.Te, GRAVITY_REACTION)
        return b[:, 0:3], b[:, 3:6], b[:, 6:9], b[:, 9:12], b[:, 12]
    omega = r.gyro - nav.gyro_bias
    # a: the mean acceleration over the step: the velocity increment less its bias and
    # gravity's reaction.
    att_T = _T(nav.attitude)
    a = r.delta_velocity / v.Te - nav.accel_bias - att_T @ GRAVITY_REACTION
    velocity = _mv(att_T, nav.velocity)
    v_g = velocity + cross3(omega, v.l_gimbal)
    return omega, a, velocity, v_g, led_bearing(nav, v.l_gimbal, v.led) - v._bearing0


def led_bearing(nav: InsState, l_gimbal: np.ndarray, led: np.ndarray) -> np.ndarray:
    """The LED's bearing from the gimbal's hinge in the hull's frame [rad] by the
    navigated pose, per vehicle (N,): ``l_gimbal`` (N, 3) the hinge in the hull's frame,
    ``led`` (N, 2) where the start put the LED [m]."""
    att, n = nav.attitude, len(nav.position)
    o = ops(n)
    r10, r00, px, py, lx, ly, ledx, ledy = columns(
        n, att[:, 1, 0], att[:, 0, 0], nav.position[:, 0], nav.position[:, 1],
        l_gimbal[:, 0], l_gimbal[:, 1], led[:, 0], led[:, 1])
    heading = o.atan2(r10, r00)
    c, s = o.cos(heading), o.sin(heading)
    dx = ledx - (px + c * lx - s * ly)
    dy = ledy - (py + s * lx + c * ly)
    bearing = o.remainder(o.atan2(dy, dx) - heading, 2 * math.pi)
    return np.array([bearing]) if n == 1 else bearing
