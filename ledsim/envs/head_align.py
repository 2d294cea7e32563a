"""``ledsim/LinkAlign-v2``: a pan-tilt head with its quad, on a physical link.

The world is ``ledsim run --gimbal pan-tilt``'s (``link="luma"`` at its 30 m by
default): the same start, noise, disturbances and tick, so with ``scenario="align"``
the episode of ``reset(seed=K)`` is seed K of that run until the actions differ.

**Observation** (``Box(low, high, (10,), float64)``; ``(7,)`` with ``imu=False``). The
powers are the link's own scale: each over the data detector's power on the boresight
at the configured distance (``peak_power``), from 20 noise standard deviations below 0
to :data:`POWER_BOUND` (the LED at half the distance), so an agent that scales by the
space's bounds sees them move (``LinkAlign-v1``'s watts span eight decades above a luma
run's 2.5e-8 W):

===  =======================================================  =====  =============
idx  observation                                              unit   bound
===  =======================================================  =====  =============
0-4  measured powers of pd0 (data), pq1-pq4, over the peak    -      see above
5    the pan's encoder angle (within one turn)                rad    +-pi
6    the tilt's encoder angle                                 rad    +-pi
7-9  the IMU's roll, pitch and yaw rates (gyro, with noise)   rad/s  +-60
===  =======================================================  =====  =============

**Action** (``Box(-1, 1, (2,), float32)``): the pan's and the tilt's torque over
``torque_limit``. **Reward**: the data detector's noise-free power over the most the
geometry allows, as in ``LinkAlign-v1``. ``info`` adds the true state ``x`` (azimuth,
elevation [rad], their rates [rad/s]).
"""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from ledsim.envs.link_align import LinkAlignEnv
from ledsim.physics.head_system import HeadSystem
from ledsim.radiometry.optics import IMPOSSIBLE_SIGMAS

#: The gyro's bound [rad/s] and the encoders' [rad].
GYRO_BOUND, ENCODER_BOUND = 60.0, math.pi
#: The powers' bound over the peak [-]: the LED at half the configured distance; a
#: closer one reads this (the observation is clipped to its space).
POWER_BOUND = 4.0


class HeadAlignEnv(LinkAlignEnv):
    """The :mod:`pan-tilt env <ledsim.envs.head_align>`: :class:`LinkAlignEnv`'s
    arguments, on a pan-tilt head (``link="luma"`` and ``gimbal="pan-tilt"`` unless
    given)."""

    def __init__(self, scenario: str | None = None, *args, **kwargs):
        kwargs.setdefault("link", "luma")
        kwargs.setdefault("gimbal", "pan-tilt")
        super().__init__(scenario, *args, **kwargs)
        c = self.system.constants
        self.scale = self.peak  # the data detector's power on the boresight [W]
        margin = IMPOSSIBLE_SIGMAS * self.measurement_noise.std / self.scale
        n = c.layout.n_photodiodes
        low = np.r_[[-margin] * n, [-ENCODER_BOUND] * 2]
        high = np.r_[[POWER_BOUND + margin] * n, [ENCODER_BOUND] * 2]
        if self.cfg.imu:
            low, high = np.r_[low, [-GYRO_BOUND] * 3], np.r_[high, [GYRO_BOUND] * 3]
        self.observation_space = spaces.Box(low, high, dtype=np.float64)

    def _system_of(self, world_config):
        if world_config.constants.layout.n_axes != 2:
            raise ValueError("gimbal='yaw': LinkAlign-v2 is the pan-tilt head's "
                             "(LinkAlign-v1 is the yaw gimbal's)")
        return HeadSystem(world_config)

    def _observe(self, reading=None):
        r = self.reading = self.sensor.read() if reading is None else reading
        info = {"x": r.x, "phi": r.phi, "phidot": r.phidot,
                "power_clean": r.power_clean.copy(), "time": self.k * self.dt}
        q = [math.remainder(a, 2 * math.pi) for a in self.world.gimbal_angles.tolist()]
        parts = [*(r.power / self.scale).tolist(), *q]
        if self.cfg.imu:
            parts += list(self.vehicle.reading.gyro)
        space = self.observation_space
        return np.minimum(np.maximum(np.array(parts), space.low), space.high), info
