"""What the water does to a hull, estimated from its IMU: a disturbance observer that
acts only on what stands out of its own noise.

The hull's equation per axis is ``M a = thrust + load``: the observer low-passes
``M a - thrust`` (a from the IMU's velocity increments for the forces, from gyro
differences for the torques), twice: fast (a gust) and slowly (a steady current, with
less noise). Its noise in still water follows from the IMU's white noise through each
low-pass (:func:`lowpass_covariance`), so it passes on only the part of each estimate
beyond ``deadband`` of those standard deviations (:func:`soft_deadband`): a hull in
still water is not pushed about by the IMU's noise.
"""

from __future__ import annotations

import numpy as np

from observer import jit
from observer.rows import Rows

compiled_loads = jit.lazy("observer.navigation.compiled_loads")
_NO_LIMIT = np.full(5, np.inf)


def soft_deadband(square, variance, k: float):
    """The share of a noisy quantity to act on, from its ``square`` and its noise's
    ``variance`` (floats or arrays): ``max(0, 1 - (k^2 variance / square)^2)``, a soft
    deadband of ``k`` standard deviations: nothing within it, 80 % at 1.5 k, nearly all
    of it well beyond. (The first power, James-Stein shrinkage, also halved the
    stiffness at twice the deadband, which cost availability in currents.)"""
    if not k:
        return 1.0
    if isinstance(square, float):
        ratio = k * k * variance / max(square, 1e-300)
        return 0.0 if ratio >= 1.0 else 1.0 - ratio * ratio
    ratio = k * k * variance / np.maximum(square, 1e-300)
    return np.maximum(0.0, 1.0 - np.minimum(ratio, 1.0) ** 2)


def lowpass_covariance(k1: float, k2: float, r0, r1):
    """Covariance of two first-order low-passes ``y += k (x - y)`` of gains k1 and k2
    fed the same stationary input of autocovariance r0 (lag 0) and r1 (lag 1, none
    beyond)."""
    a1, a2 = 1.0 - k1, 1.0 - k2
    return k1 * k2 * (r0 + r1 * (a1 + a2)) / (1.0 - a1 * a2)


class HullLoadObserver(Rows):
    """The disturbance observer of the module docstring, on the hull's surge, sway and
    heave [N] and pitch and yaw [N m].

    Args:
        Te: update period [s].
        mass: the hull's mass [kg] on the three forces and inertia [kg m^2] on the two
            torques, (5,).
        accel_noise_density: the accelerometer's [m/s^2/sqrt(Hz)].
        gyro_noise_density: the gyro's [rad/s/sqrt(Hz)] (white, sampled each Te).
        time, slow_time: the two low-passes' time constants [s].
        deadband: in standard deviations of each estimate's own noise [-].
        limit: the largest load the slow estimate believes per axis, (5,) [N, N m]
            (None: any): what the thrusters can cancel. A strike's impulse is not a
            steady load: a 3 rad/s yaw kick reads as 1e3 N m for one step, which the fast
            estimate turns into a brake for a tenth of a second, but the slow one would
            carry for seconds after it (8 seeds of a 3 rad/s hull kick: the oracle's
            availability 0.811 with both clipped, 0.847 with the slow one alone).

    Stacked (:class:`~observer.rows.Rows`), one observer serves N hulls: ``load`` and
    ``slow_load`` are then (N, 5), and :meth:`update` takes (N, 5).
    """

    ROW_ARRAYS = ("_load", "_slow_load", "_mass", "_slow_variance", "_gust_variance")

    def __init__(self, Te: float, mass, accel_noise_density: float,
                 gyro_noise_density: float, time: float, slow_time: float,
                 deadband: float, limit=None):
        self.single, self.n = True, 1
        self._mass = np.asarray(mass, dtype=float)[None]
        self.deadband = deadband
        self.limit = None if limit is None else np.asarray(limit, dtype=float)
        self._load = np.zeros((1, 5))  # fast [N, N m]
        self._slow_load = np.zeros((1, 5))
        self.k_fast = min(1.0, Te / time)
        self.k_slow = min(1.0, Te / slow_time)
        mass = self._mass[0]
        accel = accel_noise_density**2 / Te * mass[:3]**2
        gyro = gyro_noise_density**2 / (2 * Te) * (mass[3:] / Te)**2
        r0, r1 = np.r_[accel, 2 * gyro], np.r_[0.0 * accel, -gyro]  # lag 0, 1
        fast, slow = self.k_fast, self.k_slow
        slow_variance = lowpass_covariance(slow, slow, r0, r1)
        self._slow_variance = slow_variance[None]
        self._gust_variance = (lowpass_covariance(fast, fast, r0, r1) + slow_variance
                               - 2 * lowpass_covariance(fast, slow, r0, r1))[None]

    def _one(self, rows: np.ndarray) -> np.ndarray:
        return rows[0] if self.single else rows

    @property
    def mass(self) -> np.ndarray:
        """Mass [kg] and inertia [kg m^2] per axis, (5,) ((N, 5) for N hulls)."""
        return self._one(self._mass)

    @property
    def slow_variance(self) -> np.ndarray:
        """The slow estimate's noise variance in still water, per axis."""
        return self._one(self._slow_variance)

    @property
    def gust_variance(self) -> np.ndarray:
        """The fast estimate's excess's noise variance in still water, per axis."""
        return self._one(self._gust_variance)

    @property
    def load(self) -> np.ndarray:
        """The fast estimate [N, N m]."""
        return self._load[0] if self.single else self._load

    @property
    def slow_load(self) -> np.ndarray:
        """The slow estimate [N, N m]."""
        return self._slow_load[0] if self.single else self._slow_load

    def update(self, measured: np.ndarray) -> np.ndarray:
        """One period with ``M a - thrust`` (5,) [N, N m] measured ((N, 5) for N hulls);
        returns the load to cancel: the slow estimate and the fast one's excess (a gust),
        each beyond its noise."""
        measured = np.asarray(measured, dtype=float)
        out = self.update_rows(measured[None] if self.single else measured)
        return out[0] if self.single else out

    def update_rows(self, measured: np.ndarray) -> np.ndarray:
        """:meth:`update` of every hull, (N, 5)."""
        if jit.enabled():
            limit = _NO_LIMIT if self.limit is None else self.limit
            self._load, self._slow_load, out = compiled_loads.update(
                self._load, self._slow_load, np.ascontiguousarray(measured, dtype=float),
                limit, self.k_fast, self.k_slow, self._slow_variance,
                self._gust_variance, float(self.deadband))
            return out
        self._load = self._load + self.k_fast * (measured - self._load)
        if self.limit is not None:
            # np.clip's own bits, without its per-call cost on a few numbers.
            measured = np.minimum(np.maximum(measured, -self.limit), self.limit)
        self._slow_load = self._slow_load + self.k_slow * (measured - self._slow_load)
        slow, gust, k = self._slow_load, self._load - self._slow_load, self.deadband
        return slow * soft_deadband(slow**2, self._slow_variance, k) \
            + gust * soft_deadband(gust**2, self._gust_variance, k)
