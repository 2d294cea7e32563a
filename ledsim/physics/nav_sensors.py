"""The vehicle's own sensors with their noise: IMU (gyro, accelerometer), DVL, the
gimbal's encoder and an acoustic position fix.

MuJoCo's sensors (``LinkWorld.vehicle_motion``: gyro, accelerometer, velocimeter,
jointpos, framepos of the shipped scene) give the noise-free values; this module adds
what a real unit adds (:class:`~ledsim.constants.NavigationNoise`, figures and sources):

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

import numpy as np

from ledsim.constants import GRAVITY, NavigationNoise
from ledsim.physics.hull import vehicle_motion_rows
from ledsim.physics.nav_reading import NavigationReading, SensorBiases
from ledsim.physics.world import LinkWorld, WorldError
from observer import jit
from observer.navigation.rotations import rotation_log
from observer.rows import Rows

compiled_nav = jit.lazy("ledsim.physics.compiled_nav")

#: Added to the run's seed for the navigation sensors' own generator.
SEED_OFFSET = 20_000
#: What an accelerometer at rest reads: gravity's reaction, world frame [m/s^2].
GRAVITY_REACTION = np.array([0.0, 0.0, GRAVITY])


def _due(k: int, Te: float, rate: float) -> bool:
    """A measurement at ``rate`` [Hz] falls in control step ``k`` of period ``Te`` [s]
    (step 0 included)."""
    return k == 0 or math.floor(k * Te * rate + 1e-9) > math.floor((k - 1) * Te * rate + 1e-9)


class NavigationSensor(Rows):
    """The vehicle's sensors of ``world``, read once per control step ``Te`` [s].

    Args:
        world: the scene (it must have the vehicle's sensors: ``imu_gyro``, ``imu_accel``,
            ``dvl_velocity``, ``gimbal_encoder``, ``acoustic_fix``).
        Te: control period [s].
        seed: the run's seed.
        noise: the noise figures (None: :class:`~ledsim.constants.NavigationNoise`'s).

    :meth:`Rows.stacked` makes one sensor of several vehicles' (one per world, each with
    its own generators): its :meth:`read_rows` reads them all, every row as its own
    sensor would.
    """

    ROW_ARRAYS = ("gyro_bias", "accel_bias", "k", "_outliers", "surface", "_dvl",
                  "_has_dvl", "_dvl_gyro", "_attitude", "_velocity")
    ROW_LISTS = ("worlds", "rngs", "fault_rngs", "_fix_queues")

    def __init__(self, world: LinkWorld, Te: float, seed: int = 0,
                 noise: NavigationNoise | None = None):
        if world.ids.vehicle_sensors is None:
            raise WorldError(f"the scene lacks the vehicle's sensor"
                             f"{'s' if len(world.ids.missing_sensors) > 1 else ''} "
                             f"{', '.join(world.ids.missing_sensors)}: run it with --no-imu")
        self.single, self.n = True, 1
        self.worlds = [world]
        self.Te = Te
        self.noise = noise or NavigationNoise()
        n = self.noise
        self.rngs = [np.random.default_rng(SEED_OFFSET + seed)]
        self.fault_rngs = [np.random.default_rng([SEED_OFFSET + seed, 1])]  # fixes' faults
        # measured, not yet arrived: (arrival, time, fix, std)
        self._fix_queues: list[deque] = [deque()]
        self._biases = SensorBiases(np.zeros((1, 3)), np.zeros((1, 3)))  # the last reading's
        self._outliers = np.zeros(1, dtype=int)  # fixes made outliers so far
        root_bandwidth = math.sqrt(1.0 / (2.0 * Te))
        self.gyro_std = n.gyro_noise_density * root_bandwidth
        self.accel_std = n.accel_noise_density * root_bandwidth
        self.gyro_bias = self.rngs[0].standard_normal((1, 3)) * n.gyro_bias_instability
        self.accel_bias = self.rngs[0].standard_normal((1, 3)) * n.accel_bias_instability
        decay = (math.exp(-Te / n.gyro_bias_time), math.exp(-Te / n.accel_bias_time))
        self._decay = decay
        root_te = math.sqrt(Te)
        self._scale = (np.array([[self.gyro_std], [n.gyro_noise_density],
                                 [n.accel_noise_density], [self.accel_std],
                                 [n.gyro_bias_instability], [n.accel_bias_instability]]),
                       np.array([[1.0], [root_te], [root_te], [1.0],
                                 [math.sqrt(1 - decay[0]**2)],
                                 [math.sqrt(1 - decay[1]**2)]]))
        self._scale_rows = np.ascontiguousarray(np.concatenate(self._scale, axis=1).T)
        self.k = np.zeros(1, dtype=np.int64)
        self._dvl, self._has_dvl = np.zeros((1, 3)), np.zeros(1, dtype=bool)
        self._dvl_gyro = np.zeros((1, 3))
        self.surface = np.array([float(world.vehicle_motion().position[2])])  # depth 0
        self._attitude = world.hull_rotation[None]  # for the delta angle and velocity
        self._velocity = world.hull_velocity()[3:].copy()[None]  # the IMU's, world frame

    @property
    def world(self) -> LinkWorld:
        return self.worlds[0]

    @property
    def rng(self) -> np.random.Generator:
        return self.rngs[0]

    @property
    def biases(self) -> SensorBiases:
        """The IMU's biases in the last reading (each (3,); (N, 3) for N vehicles)."""
        b = self._biases
        return SensorBiases(b.gyro[0], b.accel[0]) if self.single else b

    @property
    def outliers(self):
        """Fixes made outliers so far (per vehicle for N)."""
        return int(self._outliers[0]) if self.single else self._outliers

    def read(self) -> NavigationReading:
        """The readings of this control step (the world's current state)."""
        r = self.read_rows()
        return r.row(0) if self.single else r

    def read_rows(self) -> NavigationReading:
        """Every vehicle's readings, as one :class:`NavigationReading` with a leading
        axis of N on each field (``position_fix``, ``fix_time``, ``fix_std``: NaN where
        none arrived; ``magnetometer``: None when none was read)."""
        n, Te, N = self.noise, self.Te, self.n
        truth, attitude, velocity = vehicle_motion_rows(self.worlds)
        lock = [w.dvl_bottom_lock for w in self.worlds]
        has_mag = truth.magnetometer is not None
        # Per vehicle, as plain bools (numpy's calls would cost more than the logic).
        fresh, fix_due, mag_due, dues = [], [], [], {}  # dues: per step count (mostly one)
        for k, locked, had in zip(self.k.tolist(), lock, self._has_dvl.tolist(), strict=True):
            due = dues.get(k)
            if due is None:
                due = dues[k] = (_due(k, Te, n.dvl_rate), _due(k, Te, n.fix_rate),
                                 _due(k, Te, n.magnetometer_rate) and has_mag)
            fresh.append((due[0] and locked) or not had)
            fix_due.append(due[1])
            mag_due.append(due[2])
        # Each vehicle's draws in one call, in the order a reading has always taken them.
        draws = [rng.standard_normal(18 + 3 * f + 3 * x + 1 + 3 * m) for rng, f, x, m in
                 zip(self.rngs, fresh, fix_due, mag_due, strict=True)]
        self._biases = SensorBiases(self.gyro_bias, self.accel_bias)  # replaced below
        if jit.enabled():
            gyro, delta, dv, accel, self.gyro_bias, self.accel_bias = compiled_nav.imu(
                truth.gyro, truth.accel, attitude, self._attitude, velocity, self._velocity,
                np.array([d[:18] for d in draws]), self._scale_rows, self.gyro_bias,
                self.accel_bias, self._decay[0], self._decay[1], Te, GRAVITY_REACTION)
        else:
            # The six white draws times their figures, as each line below once scaled
            # its own: gyro, delta angle, delta velocity, accelerometer, the two bias
            # drifts.
            noise = (np.array([d[:18] for d in draws]).reshape(N, 6, 3) * self._scale[0]) \
                * self._scale[1]
            gyro = truth.gyro + self.gyro_bias + noise[:, 0]
            delta = rotation_log(self._attitude.swapaxes(1, 2) @ attitude) \
                + Te * self.gyro_bias + noise[:, 1]
            dv = (attitude.swapaxes(1, 2) @ (velocity - self._velocity
                                             + Te * GRAVITY_REACTION)[..., None])[..., 0] \
                + Te * self.accel_bias + noise[:, 2]
            accel = truth.accel + self.accel_bias + noise[:, 3]
            # Gauss-Markov biases of stationary spread the bias instability.
            self.gyro_bias = self._decay[0] * self.gyro_bias + noise[:, 4]
            self.accel_bias = self._decay[1] * self.accel_bias + noise[:, 5]
        self._attitude, self._velocity = attitude, velocity
        fix, fix_time, fix_std = np.full((N, 3), np.nan), np.full(N, np.nan), np.full(N, np.nan)
        depth = np.empty(N)
        mag = np.full((N, 3), np.nan) if any(mag_due) else None
        for i, d in enumerate(draws):
            at = 18
            if fresh[i]:
                self._dvl[i] = truth.dvl[i] + d[at:at + 3] * n.dvl_noise
                self._dvl_gyro[i] = gyro[i]
                self._has_dvl[i] = True
                at += 3
            if fix_due[i]:
                self._measure_fix(i, truth.position[i], d[at:at + 3])
                at += 3
            got = self._arrived(i)
            if got[0] is not None:
                fix[i], fix_time[i], fix_std[i] = got
            depth[i] = self.surface[i] - truth.position[i, 2] + d[at] * n.depth_noise
            if mag_due[i]:
                mag[i] = truth.magnetometer[i] + d[at + 1:at + 4] * n.magnetometer_noise
        step = n.encoder_step
        encoder = np.array([step * math.floor(e / step + 0.5) for e in truth.encoder.tolist()])
        self.k = self.k + 1
        lock = np.array(lock, dtype=bool)
        return NavigationReading(gyro, accel, self._dvl.copy(), encoder, fix, depth,
                                 np.array(fresh, dtype=bool) & lock, self._dvl_gyro.copy(),
                                 delta, dv, lock, mag, fix_time, fix_std)

    def _measure_fix(self, i: int, position: np.ndarray, white: np.ndarray) -> None:
        """A fix of vehicle ``i``'s ``position`` [m] measured now: its error grows with
        the range to the transceiver, it may be an outlier, and it arrives
        ``fix_latency`` s later."""
        n, t = self.noise, int(self.k[i]) * self.Te
        r = self.worlds[i].usbl_range() or 0.0
        std = math.hypot(n.fix_noise, n.fix_range_error * r)
        fix = position + white * std
        if n.fix_outlier_share > 0:
            faults = self.fault_rngs[i]
            outlier = faults.random() < n.fix_outlier_share
            extra = faults.standard_normal(3) * n.fix_outlier_size
            if outlier:
                fix = fix + extra
                self._outliers[i] += 1
        self._fix_queues[i].append((t + n.fix_latency, t, fix, std))

    def _arrived(self, i: int) -> tuple[np.ndarray | None, float | None, float | None]:
        """The fix of vehicle ``i`` that arrives this step (the latest, if several did),
        its measurement time [s] and expected error [m]; Nones when none arrives."""
        t, got, queue = int(self.k[i]) * self.Te, (None, None, None), self._fix_queues[i]
        while queue and queue[0][0] <= t + 1e-9:
            _, measured, fix, std = queue.popleft()
            got = (fix, measured, std)
        return got
