"""The IMU's part of the navigation sensors' reading, compiled
(:meth:`~ledsim.physics.nav_sensors.NavigationSensor.read_rows` stays the reference and
calls this when :func:`observer.jit.enabled`): the same formulas, one vehicle (row) at a
time, on the white draws the reference's generators gave."""

from __future__ import annotations

import math

import numpy as np

from observer.jit import njit


@njit()
def _log(R: np.ndarray, out: np.ndarray) -> None:
    """The rotation vector [rad] of R into ``out`` (``rotations._log_one``)."""
    angle = math.acos(max(-1.0, min(1.0, 0.5 * ((R[0, 0] + R[1, 1] + R[2, 2]) - 1.0))))
    out[0], out[1], out[2] = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    if angle < 1e-9:
        for i in range(3):
            out[i] = 0.5 * out[i]
    else:
        f = 2.0 * math.sin(angle)
        for i in range(3):
            out[i] = out[i] * angle / f


@njit()
def imu(true_gyro, true_accel, attitude, prev_attitude, velocity, prev_velocity, white,
        scale, gyro_bias, accel_bias, decay_gyro, decay_accel, Te, reaction):
    """Every vehicle's gyro [rad/s], delta angle [rad], delta velocity [m/s] and
    accelerometer [m/s^2] (each (N, 3)), and the biases' next values: (gyro, delta,
    dv, accel, gyro bias, accel bias). ``white`` (N, 18): the six white draws of each
    vehicle; ``scale`` (2, 6): their two factors (``NavigationSensor._scale``)."""
    n = true_gyro.shape[0]
    gyro, delta, dv = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    accel, bg, ba = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    noise, turn, rel = np.empty((6, 3)), np.empty((3, 3)), np.empty(3)
    for r in range(n):
        for j in range(6):
            for i in range(3):
                noise[j, i] = (white[r, 3 * j + i] * scale[0, j]) * scale[1, j]
        for i in range(3):
            for j in range(3):
                s = 0.0
                for q in range(3):
                    s += prev_attitude[r, q, i] * attitude[r, q, j]
                turn[i, j] = s
        _log(turn, delta[r])
        for i in range(3):
            rel[i] = velocity[r, i] - prev_velocity[r, i] + Te * reaction[i]
        for i in range(3):
            s = 0.0
            for q in range(3):
                s += attitude[r, q, i] * rel[q]
            gyro[r, i] = true_gyro[r, i] + gyro_bias[r, i] + noise[0, i]
            delta[r, i] = delta[r, i] + Te * gyro_bias[r, i] + noise[1, i]
            dv[r, i] = s + Te * accel_bias[r, i] + noise[2, i]
            accel[r, i] = true_accel[r, i] + accel_bias[r, i] + noise[3, i]
            bg[r, i] = decay_gyro * gyro_bias[r, i] + noise[4, i]
            ba[r, i] = decay_accel * accel_bias[r, i] + noise[5, i]
    return gyro, delta, dv, accel, bg, ba
