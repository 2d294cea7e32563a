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


class LineOfSightFilter:
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
    """

    def __init__(self, Te: float, distance: float, rate_noise: float,
                 rate_time: float = 0.05, bearing_time: float = 2.0,
                 reanchor_rate: float = 3.0, reanchor_time: float = 1.0,
                 reanchor_bearing_time: float = 0.2):
        self.Te, self.distance, self.rate_noise = Te, distance, rate_noise
        self.k_rate, self.k_power = min(1.0, Te / rate_time), min(1.0, Te / 0.5)
        self.k_bearing = min(1.0, Te / bearing_time)
        self.reanchor_rate, self.reanchor_time = reanchor_rate, reanchor_time
        self.k_reanchor = min(1.0, Te / reanchor_bearing_time)
        self.los = LineOfSight()
        self._raw = self._power = self._anchor = 0.0
        self.k = 0

    def update(self, v_gimbal, encoder: float, hull_rate: float,
               nav_bearing: float) -> LineOfSight:
        """One step: the hinge's velocity (3,) [m/s] in the hull's frame, the encoder
        angle [rad], the hull's yaw rate [rad/s] and the bearing the navigated pose
        gives, since the start [rad]."""
        c, s = math.cos(encoder), math.sin(encoder)
        raw = (-c * v_gimbal[1] + s * v_gimbal[0]) / self.distance
        self._raw += self.k_rate * (raw - self._raw)
        self._power += self.k_power * (self._raw**2 - self._power)
        rate = self._raw * max(0.0, 1.0 - self.rate_noise**2 / max(self._power, 1e-30))
        accel = (rate - self.los.rate) / self.Te if self.k else 0.0
        bearing = self.los.bearing + self.Te * (rate - hull_rate)
        if abs(raw) > self.reanchor_rate:
            self._anchor = self.reanchor_time
        k = self.k_bearing
        if self._anchor > 0:
            k, self._anchor = self.k_reanchor, self._anchor - self.Te
        bearing += k * math.remainder(nav_bearing - bearing, 2 * math.pi)
        self.los = LineOfSight(rate, accel, hull_rate, bearing)
        self.k += 1
        return self.los
