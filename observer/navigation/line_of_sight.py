"""The line of sight from a moving vehicle to the LED: its bearing rate at the receiver
and its bearing in the hull's frame, estimated from the vehicle's navigation.

The gimbal's hinge moves with the hull at v_g (hull frame); the receiver's axis is
u = (cos q, sin q) (encoder q), close to the LED's direction while aligned; d is the
link distance the run is told. Then

    w = (u x (-v_g))_z / d                 the LED's bearing rate [rad/s]

w is low-passed over ``rate_time`` and shrunk by the share of its power that is the
sensors' noise (a Wiener gain: a still hull's w is that noise alone, and fed forward it
would only turn the gimbal by it). The bearing in the hull's frame integrates
``w - r`` (r the hull's yaw rate) and is pulled towards the bearing the navigated pose
gives, over ``bearing_time``; after a violent excursion (w beyond ``reanchor_rate``, a
hull strike's) over ``reanchor_bearing_time`` for ``reanchor_time``: the small-angle,
one-sample-a-step integration of w is wrong by tenths of a radian once a strike swings
the hinge by a large part of d, and the navigation's geometry is not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from observer import jit
from observer.rowops import columns, ops
from observer.rows import Rows

compiled_sight = jit.lazy("observer.navigation.compiled_sight")


@dataclass
class LineOfSight:
    """What the vehicle measured of the line of sight this step.

    Attributes:
        rate: the LED's bearing rate at the receiver from the hull's motion [rad/s].
        acceleration: its change over the last step [rad/s^2]: the input the hull's
            motion adds to phi'' (the gimbal itself is inertially free on its hinge).
        hull_rate: the gyro's yaw rate [rad/s].
        bearing: how far the LED's bearing in the hull's frame has turned since the
            start [rad] (see the module docstring).
    """

    rate: float = 0.0
    acceleration: float = 0.0
    hull_rate: float = 0.0
    bearing: float = 0.0

    @property
    def incidence_rate(self) -> float:
        """phidot [rad/s] from the encoder rate is ``rate - hull_rate - qdot``."""
        return self.rate - self.hull_rate


def _constant(index: int, doc: str) -> property:
    """One of :class:`LineOfSightFilter`'s constants, read from and written to its
    ``_constants`` array."""
    return property(lambda self: float(self._constants[index]),
                    lambda self, value: self._constants.__setitem__(index, value), doc=doc)


class LineOfSightFilter(Rows):
    """The estimator of the module docstring.

    Args:
        Te: step [s].
        distance: the link distance the run is told [m].
        rate_noise: the noise the raw w carries after the low-pass [rad/s] (from the
            sensors' figures).
        rate_time: the low-pass's time constant [s].
        bearing_time: the bearing's pull towards the navigation's [s].
        reanchor_rate [rad/s], reanchor_time [s], reanchor_bearing_time [s]: the pull
            after a violent excursion.

    Stacked (:class:`~observer.rows.Rows`), one filter serves N vehicles:
    :meth:`update_rows` takes their arrays and :meth:`los_of` gives each one's.
    """

    ROW_ARRAYS = ("rate", "acceleration", "hull_rate", "bearing", "_raw", "_power",
                  "_anchor", "k", "_noise_power", "ranges")

    def __init__(self, Te: float, distance: float, rate_noise: float,
                 rate_time: float = 0.05, bearing_time: float = 2.0,
                 reanchor_rate: float = 3.0, reanchor_time: float = 1.0,
                 reanchor_bearing_time: float = 0.2):
        # The filter's constants live in the one array the compiled step takes (their
        # names are properties over it: a change reaches both paths).
        self._constants = np.array([min(1.0, Te / rate_time), min(1.0, Te / 0.5), Te,
                                    reanchor_rate, reanchor_time,
                                    min(1.0, Te / reanchor_bearing_time),
                                    min(1.0, Te / bearing_time)], float)
        self.distance, self.rate_noise = distance, rate_noise
        self.single, self.n = True, 1
        self._noise_power = np.array([rate_noise**2])
        self.rate, self.acceleration = np.zeros(1), np.zeros(1)
        self.hull_rate, self.bearing = np.zeros(1), np.zeros(1)
        self._raw, self._power, self._anchor = np.zeros(1), np.zeros(1), np.zeros(1)
        self.k = np.zeros(1, dtype=np.int64)
        #: Each vehicle's range to the LED [m]: the told distance, or where a moving
        #: vehicle's navigation puts it (set by its owner each step).
        self.ranges = np.array([float(distance)])

    k_rate = _constant(0, "the rate's low-pass gain a step [-]")
    k_power = _constant(1, "the rate power's low-pass gain a step [-]")
    Te = _constant(2, "the step [s]")
    reanchor_rate = _constant(3, "the rate that counts as a violent excursion [rad/s]")
    reanchor_time = _constant(4, "how long the stronger pull lasts after one [s]")
    k_reanchor = _constant(5, "the bearing's pull a step after one [-]")
    k_bearing = _constant(6, "the bearing's pull a step [-]")

    def los_of(self, i: int) -> LineOfSight:
        """Vehicle ``i``'s line of sight at its last step."""
        return LineOfSight(float(self.rate[i]), float(self.acceleration[i]),
                           float(self.hull_rate[i]), float(self.bearing[i]))

    @property
    def los(self) -> LineOfSight:
        """What the (first) vehicle measured of the line of sight at its last step."""
        return self.los_of(0)

    def update(self, v_gimbal, encoder: float, hull_rate: float,
               nav_bearing: float) -> LineOfSight:
        """One step: the hinge's velocity (3,) [m/s] in the hull's frame, the encoder
        angle [rad], the hull's yaw rate [rad/s] and the bearing the navigated pose
        gives, since the start [rad]."""
        self.update_rows(np.asarray(v_gimbal, dtype=float)[None], np.array([encoder]),
                         np.array([hull_rate]), np.array([nav_bearing]))
        return self.los

    def update_rows(self, v_gimbal: np.ndarray, encoder: np.ndarray, hull_rate: np.ndarray,
                    nav_bearing: np.ndarray) -> None:
        """:meth:`update` of every vehicle: (N, 3), (N,), (N,), (N,)."""
        n = self.n
        state = (self._raw, self._power, self.rate, self.bearing, self._anchor)
        # the rate's noise goes as 1 / range: its power at each vehicle's range now
        noise = self._noise_power * np.square(self.distance / self.ranges)
        if jit.enabled():
            new = compiled_sight.step(*state, self.k, v_gimbal, encoder, hull_rate,
                                      nav_bearing, noise, self.ranges, self._constants)
            self._raw, self._power, self.rate, self.bearing, self._anchor, \
                self.acceleration, self.hull_rate = new
            self.k = self.k + 1
            return
        new = _step(ops(n), self, *columns(n, *state, self.k > 0, v_gimbal[:, 0],
                                           v_gimbal[:, 1], encoder, hull_rate, nav_bearing,
                                           noise, self.ranges))
        if n == 1:  # in place: no one holds these arrays
            for arr, value in zip((*state, self.acceleration, self.hull_rate),
                                  new, strict=True):
                arr[0] = value
            self.k[0] += 1
            return
        self._raw, self._power, self.rate, self.bearing, self._anchor, \
            self.acceleration, self.hull_rate = new
        self.k = self.k + 1


def _step(o, f: LineOfSightFilter, raw, power, rate, bearing, anchor, started, vx, vy,
          encoder, hull_rate, nav_bearing, noise_power, ranges):
    """One step of the filter's state, each argument a float (one vehicle) or a column
    of N (``o``: :mod:`observer.rowops`); returns the new (raw, power, rate, bearing,
    anchor, acceleration, hull rate)."""
    c, s = o.cos(encoder), o.sin(encoder)
    w = (-c * vy + s * vx) / ranges
    raw = raw + f.k_rate * (w - raw)
    power = power + f.k_power * (o.square(raw) - power)
    new_rate = raw * o.maximum(0.0, 1.0 - noise_power / o.maximum(power, 1e-30))
    accel = o.where(started, (new_rate - rate) / f.Te, 0.0)
    bearing = bearing + f.Te * (new_rate - hull_rate)
    anchor = o.where(o.abs(w) > f.reanchor_rate, f.reanchor_time, anchor)
    pulled = anchor > 0
    k = o.where(pulled, f.k_reanchor, f.k_bearing)
    anchor = o.where(pulled, anchor - f.Te, anchor)
    bearing = bearing + k * o.remainder(nav_bearing - bearing, 2 * math.pi)
    return raw, power, new_rate, bearing, anchor, accel, hull_rate * 1.0
