"""The vehicle's own sensors with their noise: IMU (gyro, accelerometer), DVL, the
gimbal's encoder and an acoustic position fix.

MuJoCo's sensors (``LinkWorld.vehicle_motion``: gyro, accelerometer, velocimeter,
jointpos, framepos of the shipped scene) give the noise-free values; this module adds
what a real unit adds (:class:`~ledsim.config.NavigationNoise`, figures and sources):

==============  =======================================================  ===========
reading         noise                                                    unit
==============  =======================================================  ===========
gyro            white (angle random walk) + a drifting bias             rad/s
delta_angle     the orientation increment over the step (the IMU's       rad
                strapdown output, as the MTi-1's DeltaQ), with the
                same noise integrated over the step
delta_velocity  the specific force integrated over the step, in the      m/s
                IMU's frame (the MTi-1's DeltaV), with the
                accelerometer's noise integrated over the step
accel           white (velocity random walk) + a drifting bias          m/s^2
dvl             white per ping; the last ping held between pings         m/s
encoder         quantised to the encoder's step                          rad
position_fix    white, once per fix interval (None between fixes); it    m
                may arrive late, grow with the range to the USBL
                transceiver and be an outlier (the ``fix_*`` figures)
depth           white (a pressure sensor), every step; positive down    m
magnetometer    white, at the magnetometer's rate (None between)         T
==============  =======================================================  ===========

The DVL pings only while it has bottom lock (``LinkWorld.dvl_bottom_lock``, which the
``dvl_dropout`` disturbance takes away). Its random numbers come from generators of its
own, seeded from the run's seed, so turning the IMU on or off never changes the
photodiodes' noise, and turning the fixes' faults on never changes the other sensors'.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from observer.rotations import rotation_log

from ..config import GRAVITY, NavigationNoise
from .world import LinkWorld, WorldError

#: Added to the run's seed for the navigation sensors' own generator.
SEED_OFFSET = 20_000
#: What an accelerometer at rest reads: gravity's reaction, world frame [m/s^2].
GRAVITY_REACTION = np.array([0.0, 0.0, GRAVITY])


@dataclass
class NavigationReading:
    """One control step of the vehicle's sensors, with their noise (see the module
    docstring): gyro (3,) [rad/s] and accel (3,) [m/s^2] in the IMU frame, dvl (3,)
    [m/s] in the DVL frame, encoder [rad], position_fix (3,) [m] in the world frame or
    None when no fix arrived this step, depth [m] of the IMU below its start, positive
    down (a pressure sensor), dvl_fresh: the DVL pinged this step, dvl_gyro: the gyro's
    reading at the DVL's last ping (to take the lever arm off that ping's velocity),
    delta_angle (3,) [rad]: the IMU's orientation increment since the last step, in its
    frame; delta_velocity (3,) [m/s]: the specific force integrated since the last
    step, in its current frame (a strike's velocity change included, which a sampled
    accelerometer misses); dvl_valid: the DVL has bottom lock (else ``dvl`` is the last
    ping, stale); magnetometer (3,) [T] in the IMU frame, or None when none arrived this
    step; fix_time [s]: when the fix that arrived was measured; fix_std [m]: the fix's
    expected error, each axis, as the USBL reports it (its outliers not included)."""

    gyro: np.ndarray
    accel: np.ndarray
    dvl: np.ndarray
    encoder: float
    position_fix: np.ndarray | None
    depth: float = 0.0
    dvl_fresh: bool = True
    dvl_gyro: np.ndarray | None = None
    delta_angle: np.ndarray | None = None
    delta_velocity: np.ndarray | None = None
    dvl_valid: bool = True
    magnetometer: np.ndarray | None = None
    fix_time: float | None = None
    fix_std: float | None = None


@dataclass(frozen=True)
class SensorBiases:
    """The IMU's biases in a reading: gyro (3,) [rad/s] and accelerometer (3,)
    [m/s^2] (the truth a navigation filter's estimate is measured against)."""

    gyro: np.ndarray
    accel: np.ndarray


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
            raise WorldError(f"the scene lacks the vehicle's sensor"
                             f"{'s' if len(world.ids.missing_sensors) > 1 else ''} "
                             f"{', '.join(world.ids.missing_sensors)}: run it with --no-imu")
        self.world = world
        self.Te = Te
        self.noise = noise or NavigationNoise()
        n = self.noise
        self.rng = np.random.default_rng(SEED_OFFSET + seed)
        self.fault_rng = np.random.default_rng([SEED_OFFSET + seed, 1])  # fixes' faults
        self._fixes: deque = deque()  # measured, not yet arrived: (arrival, time, fix, std)
        self.biases = SensorBiases(np.zeros(3), np.zeros(3))  # of the last reading
        self.outliers = 0  # fixes made outliers so far
        root_bandwidth = math.sqrt(1.0 / (2.0 * Te))
        self.gyro_std = n.gyro_noise_density * root_bandwidth
        self.accel_std = n.accel_noise_density * root_bandwidth
        self.gyro_bias = self.rng.standard_normal(3) * n.gyro_bias_instability
        self.accel_bias = self.rng.standard_normal(3) * n.accel_bias_instability
        self._decay = (math.exp(-Te / n.gyro_bias_time), math.exp(-Te / n.accel_bias_time))
        self.k = 0
        self._dvl: np.ndarray | None = None
        self.surface = float(world.vehicle_motion().position[2])  # depth 0: the start
        self._attitude = world.hull_rotation  # for the delta angle and velocity
        self._velocity = world.hull_velocity()[3:].copy()  # the IMU's, world frame

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
        attitude = self.world.hull_rotation
        delta = rotation_log(self._attitude.T @ attitude) + self.Te * self.gyro_bias \
            + rng.standard_normal(3) * n.gyro_noise_density * math.sqrt(self.Te)
        self._attitude = attitude
        velocity = self.world.hull_velocity()[3:].copy()
        dv = attitude.T @ (velocity - self._velocity + self.Te * GRAVITY_REACTION) \
            + self.Te * self.accel_bias \
            + rng.standard_normal(3) * n.accel_noise_density * math.sqrt(self.Te)
        self._velocity = velocity
        accel = truth.accel + self.accel_bias + rng.standard_normal(3) * self.accel_std
        self.biases = SensorBiases(self.gyro_bias.copy(), self.accel_bias.copy())
        self.gyro_bias = self._drift(self.gyro_bias, self._decay[0], n.gyro_bias_instability)
        self.accel_bias = self._drift(self.accel_bias, self._decay[1],
                                      n.accel_bias_instability)
        lock = self.world.dvl_bottom_lock
        fresh = (self._due(n.dvl_rate) and lock) or self._dvl is None
        if fresh:
            self._dvl = truth.dvl + rng.standard_normal(3) * n.dvl_noise
            self._dvl_gyro = gyro.copy()
        if self._due(n.fix_rate):
            self._measure_fix(truth.position, rng.standard_normal(3))
        fix, fix_time, fix_std = self._arrived()
        step = n.encoder_step
        encoder = step * math.floor(truth.encoder / step + 0.5)
        depth = self.surface - truth.position[2] + rng.standard_normal() * n.depth_noise
        mag = None
        if truth.magnetometer is not None and self._due(n.magnetometer_rate):
            mag = truth.magnetometer + rng.standard_normal(3) * n.magnetometer_noise
        self.k += 1
        return NavigationReading(gyro, accel, self._dvl.copy(), encoder, fix, float(depth),
                                 fresh and lock, self._dvl_gyro.copy(), delta, dv, lock, mag,
                                 fix_time, fix_std)

    def _measure_fix(self, position: np.ndarray, white: np.ndarray) -> None:
        """A fix of ``position`` [m] measured now: its error grows with the range to the
        transceiver, it may be an outlier, and it arrives ``fix_latency`` s later."""
        n, t = self.noise, self.k * self.Te
        r = self.world.usbl_range() or 0.0
        std = math.hypot(n.fix_noise, n.fix_range_error * r)
        fix = position + white * std
        if n.fix_outlier_share > 0:
            outlier = self.fault_rng.random() < n.fix_outlier_share
            extra = self.fault_rng.standard_normal(3) * n.fix_outlier_size
            if outlier:
                fix = fix + extra
                self.outliers += 1
        self._fixes.append((t + n.fix_latency, t, fix, std))

    def _arrived(self) -> tuple[np.ndarray | None, float | None, float | None]:
        """The fix that arrives this step (the latest, if several did), its measurement
        time [s] and expected error [m]; Nones when none arrives."""
        t, got = self.k * self.Te, (None, None, None)
        while self._fixes and self._fixes[0][0] <= t + 1e-9:
            _, measured, fix, std = self._fixes.popleft()
            got = (fix, measured, std)
        return got
