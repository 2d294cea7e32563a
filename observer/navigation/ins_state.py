"""What the aided INS (:mod:`observer.navigation.ins`) is told and what it estimates: its sensors'
noise figures and its state."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class InertialNoise:
    """What the filter knows of its sensors' noise (SI units).

    Attributes:
        gyro_noise_density: angle random walk [rad/s/sqrt(Hz)].
        gyro_bias_instability: stationary spread of the gyro bias [rad/s].
        gyro_bias_time: its correlation time [s].
        accel_noise_density: velocity random walk [m/s^2/sqrt(Hz)].
        accel_bias_instability: stationary spread of the accelerometer bias [m/s^2].
        accel_bias_time: its correlation time [s].
        dvl_noise: one DVL ping's velocity noise, each axis [m/s].
        depth_noise: one depth reading's noise [m].
        magnetometer_noise: one magnetometer reading's noise, each axis [field unit].
    """

    gyro_noise_density: float
    gyro_bias_instability: float
    gyro_bias_time: float
    accel_noise_density: float
    accel_bias_instability: float
    accel_bias_time: float
    dvl_noise: float
    depth_noise: float
    magnetometer_noise: float


@dataclass
class InsState:
    """The filter's estimate: position (3,) [m] and velocity (3,) [m/s] in the world
    frame (z up), attitude (3x3, body to world), gyro bias (3,) [rad/s] and accelerometer
    bias (3,) [m/s^2]."""

    position: np.ndarray
    velocity: np.ndarray
    attitude: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray

    @property
    def heading(self) -> float:
        """Yaw of the body's x axis about world z [rad]."""
        return math.atan2(self.attitude[1, 0], self.attitude[0, 0])

    @property
    def pitch(self) -> float:
        """Pitch of the body's x axis above the horizontal, nose down positive [rad]."""
        return math.asin(max(-1.0, min(1.0, -self.attitude[2, 0])))

    def copy(self) -> InsState:
        return InsState(self.position.copy(), self.velocity.copy(), self.attitude.copy(),
                        self.gyro_bias.copy(), self.accel_bias.copy())
