"""The vehicle's own sensors with their noise: IMU (gyro, accelerometer), DVL, the
gimbal's encoder and an acoustic position fix.

MuJoCo's sensors (``LinkWorld.vehicle_motion``: gyro, accelerometer, velocimeter,
jointpos, framepos of the shipped scene) give the noise-free values; this module adds
what a real unit adds (:class:`~ledsim.config.NavigationNoise`, figures and sources):

==============  =======================================================  ===========
reading         noise                                                    unit
==============  =======================================================  ===========
gyro            white (angle random walk) + a drifting bias             rad/s
accel           white (velocity random walk) + a drifting bias          m/s^2
dvl             white per ping; the last ping held between pings         m/s
encoder         quantised to the encoder's step                          rad
position_fix    white, once per fix interval (None between fixes)        m
depth           white (a pressure sensor), every step; positive down    m
==============  =======================================================  ===========

Its random numbers come from a generator of its own, seeded from the run's seed, so
turning the IMU on or off never changes the photodiodes' noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import NavigationNoise
from .world import LinkWorld, WorldError

#: Added to the run's seed for the navigation sensors' own generator.
SEED_OFFSET = 20_000


@dataclass
class NavigationReading:
    """One control step of the vehicle's sensors, with their noise (see the module
    docstring): gyro (3,) [rad/s] and accel (3,) [m/s^2] in the IMU frame, dvl (3,)
    [m/s] in the DVL frame, encoder [rad], position_fix (3,) [m] in the world frame or
    None when no fix arrived this step, depth [m] of the IMU below its start, positive
    down (a pressure sensor), dvl_fresh: the DVL pinged this step, dvl_gyro: the gyro's
    reading at the DVL's last ping (to take the lever arm off that ping's velocity)."""

    gyro: np.ndarray
    accel: np.ndarray
    dvl: np.ndarray
    encoder: float
    position_fix: np.ndarray | None
    depth: float = 0.0
    dvl_fresh: bool = True
    dvl_gyro: np.ndarray | None = None


class NavigationSensor:
    """The vehicle's sensors of ``world``, read once per control step ``Te`` [s].

    Args:
        world: the scene (it must have the vehicle's sensors: ``imu_gyro``, ``imu_accel``,
            ``dvl_velocity``, ``gimbal_encoder``, ``acoustic_fix``).
        Te: control period [s].
        seed: the run's seed.
        noise: the noise figures (None: :class:`~ledsim.config.NavigationNoise`'s).
    """

    def __init__(self, world: LinkWorld, Te: float, seed: int = 0,
                 noise: NavigationNoise | None = None):
        if world.ids.vehicle_sensors is None:
            raise WorldError("the scene has no IMU, DVL, encoder or position-fix sensor "
                             "(imu_gyro, imu_accel, dvl_velocity, gimbal_encoder, "
                             "acoustic_fix): run it with --no-imu")
        self.world = world
        self.Te = Te
        self.noise = noise or NavigationNoise()
        n = self.noise
        self.rng = np.random.default_rng(SEED_OFFSET + seed)
        root_bandwidth = math.sqrt(1.0 / (2.0 * Te))
        self.gyro_std = n.gyro_noise_density * root_bandwidth
        self.accel_std = n.accel_noise_density * root_bandwidth
        self.gyro_bias = self.rng.standard_normal(3) * n.gyro_bias_instability
        self.accel_bias = self.rng.standard_normal(3) * n.accel_bias_instability
        self._decay = (math.exp(-Te / n.gyro_bias_time), math.exp(-Te / n.accel_bias_time))
        self.k = 0
        self._dvl: np.ndarray | None = None
        self.surface = float(world.vehicle_motion().position[2])  # depth 0: the start

    def _due(self, rate: float) -> bool:
        """A measurement at ``rate`` [Hz] falls in this control step (step 0 included)."""
        k = self.k
        return k == 0 or math.floor(k * self.Te * rate + 1e-9) > \
            math.floor((k - 1) * self.Te * rate + 1e-9)

    def _drift(self, bias: np.ndarray, decay: float, spread: float) -> np.ndarray:
        """One step of a Gauss-Markov bias with stationary spread ``spread``."""
        return decay * bias + self.rng.standard_normal(3) * spread * math.sqrt(1 - decay**2)

    def read(self) -> NavigationReading:
        """The readings of this control step (the world's current state)."""
        truth = self.world.vehicle_motion()
        n, rng = self.noise, self.rng
        gyro = truth.gyro + self.gyro_bias + rng.standard_normal(3) * self.gyro_std
        accel = truth.accel + self.accel_bias + rng.standard_normal(3) * self.accel_std
        self.gyro_bias = self._drift(self.gyro_bias, self._decay[0], n.gyro_bias_instability)
        self.accel_bias = self._drift(self.accel_bias, self._decay[1],
                                      n.accel_bias_instability)
        fresh = self._due(n.dvl_rate) or self._dvl is None
        if fresh:
            self._dvl = truth.dvl + rng.standard_normal(3) * n.dvl_noise
            self._dvl_gyro = gyro.copy()
        fix = truth.position + rng.standard_normal(3) * n.fix_noise \
            if self._due(n.fix_rate) else None
        step = n.encoder_step
        encoder = step * math.floor(truth.encoder / step + 0.5)
        depth = self.surface - truth.position[2] + rng.standard_normal() * n.depth_noise
        self.k += 1
        return NavigationReading(gyro, accel, self._dvl.copy(), encoder, fix, float(depth),
                                 fresh, self._dvl_gyro.copy())
