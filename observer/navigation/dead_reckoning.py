"""A vehicle's horizontal navigation from its gyro, DVL and acoustic fixes.

Dead reckoning, corrected by the fixes (a complementary filter), in the horizontal
plane of a vehicle that stays level:

    heading     psi' = psi + dpsi                        dpsi: the IMU's yaw increment
                                                         (else Te (r + r_prev) / 2)
    velocity    v_b  = R_dvl d - omega x l_dvl            d: the DVL's reading, in its frame
                v    = Rz(psi) v_b[:2]                    (the DVL sees the lever arm l_dvl)
    position    p'   = p + Te v,   and at a fix f:  p <- p + g (f - p)

The heading is dead-reckoned from the known start: a gyro bias of 10 deg/h moves it by
0.06 deg in 20 s. Numpy only; the vehicle (``ledsim.agent.autopilot``) feeds it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class NavigationState:
    """position (2,) [m] and velocity (2,) [m/s] in the world's horizontal plane, heading
    psi [rad] and yaw rate r [rad/s]."""

    position: np.ndarray
    velocity: np.ndarray
    heading: float
    yaw_rate: float


class DeadReckoning:
    """The complementary filter of the module docstring.

    Args:
        Te: update period [s].
        position: the start's horizontal position [m], (2,).
        heading: the start's heading [rad].
        dvl_rotation: the DVL frame in the body frame, 3x3.
        dvl_lever: the DVL's position from the IMU, body frame [m], (3,).
        fix_gain: share of a fix's innovation taken into the position [-].
    """

    def __init__(self, Te: float, position, heading: float, dvl_rotation, dvl_lever,
                 fix_gain: float = 0.2):
        self.Te = Te
        self.R_dvl = np.asarray(dvl_rotation, dtype=float)
        self.lever = np.asarray(dvl_lever, dtype=float)
        self.fix_gain = fix_gain
        self.state = NavigationState(np.array(position, dtype=float)[:2], np.zeros(2),
                                     float(heading), 0.0)

    def update(self, gyro, dvl, fix=None, velocity=None, delta_yaw=None) -> NavigationState:
        """One period: the gyro (3,) [rad/s] and DVL (3,) [m/s] readings, and an acoustic
        fix of the position (3,) [m] when one arrived (else None). ``velocity``: the
        hull's velocity at the IMU in its own frame (3,) [m/s] from a better source
        (an accelerometer-aided filter), used instead of the DVL's."""
        s = self.state
        gyro = np.asarray(gyro, dtype=float)
        rate_before, s.yaw_rate = s.yaw_rate, float(gyro[2])
        v_body = (self.R_dvl @ np.asarray(dvl, dtype=float) - np.cross(gyro, self.lever)
                  if velocity is None else np.asarray(velocity, dtype=float))
        heading = s.heading + (0.5 * self.Te * (rate_before + s.yaw_rate)  # trapezoid
                               if delta_yaw is None else float(delta_yaw))
        mid = 0.5 * (s.heading + heading)
        c, si = math.cos(mid), math.sin(mid)
        s.velocity = np.array([c * v_body[0] - si * v_body[1], si * v_body[0] + c * v_body[1]])
        s.position = s.position + self.Te * s.velocity
        s.heading = heading
        if fix is not None:
            s.position = s.position + self.fix_gain * (np.asarray(fix, dtype=float)[:2]
                                                       - s.position)
        return s
