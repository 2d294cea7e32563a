"""What the vehicle's navigation sensors give at one control step
(:class:`NavigationReading`, made by :class:`~ledsim.physics.nav_sensors.NavigationSensor`),
and the IMU biases in it (:class:`SensorBiases`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np


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

    @classmethod
    def stacked(cls, readings) -> NavigationReading:
        """The readings of several sets of vehicles (each taken for its rows), as one
        taken for all their rows (a field none has stays None; one some lack, NaN)."""
        out = {}
        for f in fields(cls):
            values = [getattr(r, f.name) for r in readings]
            present = [v for v in values if v is not None]
            if not present:
                out[f.name] = None
                continue
            blank = np.full_like(np.asarray(present[0], dtype=float), np.nan)
            out[f.name] = np.concatenate([blank if v is None else np.asarray(v)
                                          for v in values])
        return cls(**out)

    def row(self, i: int) -> NavigationReading:
        """Vehicle ``i``'s reading of one taken for N vehicles (NaN fixes as None)."""
        fixed = not math.isnan(self.fix_time[i])
        mag = self.magnetometer
        return NavigationReading(
            self.gyro[i], self.accel[i], self.dvl[i], float(self.encoder[i]),
            self.position_fix[i] if fixed else None, float(self.depth[i]),
            bool(self.dvl_fresh[i]), self.dvl_gyro[i], self.delta_angle[i],
            self.delta_velocity[i], bool(self.dvl_valid[i]),
            None if mag is None or math.isnan(mag[i, 0]) else mag[i],
            float(self.fix_time[i]) if fixed else None,
            float(self.fix_std[i]) if fixed else None)


@dataclass(frozen=True)
class SensorBiases:
    """The IMU's biases in a reading: gyro (3,) [rad/s] and accelerometer (3,)
    [m/s^2] (the truth a navigation filter's estimate is measured against)."""

    gyro: np.ndarray
    accel: np.ndarray
