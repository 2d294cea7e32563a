"""The single env's observation, reward and ``info`` for N sub-environments at once.

:class:`~ledsim.envs.vector.LinkAlignVectorEnv` steps N worlds in one tick; observing
and rewarding each one through :meth:`LinkAlignEnv.observe_step
<ledsim.envs.link_align.LinkAlignEnv.observe_step>` costs numpy's per-call overhead N
times a step (a dozen small calls each). Here the same operations run over the N rows:
elementwise IEEE arithmetic and numpy's own ``exp``, ``cos`` and square, which give
each element the bits they give it alone, and libm's ``pow`` and ``remainder`` per
element where the single env calls them on a numpy scalar or a float (numpy's array
``power`` differs from libm's in the last bit). ``tests/test_vector_env.py`` holds every
row to the single env's bits.
"""

from __future__ import annotations

import math

import numpy as np

from ledsim.constants import LinkConstants
from ledsim.physics.sensor import SensorReading
from observer.navigation.rotations import per_element


def observe_rows(envs, readings: list[SensorReading], vehicles) -> tuple:
    """(obs (N, n_obs), reward (N,), info of arrays (N, ...)) of ``envs`` (N
    :class:`~ledsim.envs.link_align.LinkAlignEnv` of one configuration, each with its
    vehicle a row of the stacked ``vehicles``; read only with the IMU) from their
    sensors' ``readings`` (None: the env reads its own now); each env's
    :attr:`reading` is set, as its own :meth:`observe_step` sets it. Row i is what
    ``envs[i].observe_step(readings[i])`` returns, to the last bit."""
    e0 = envs[0]
    readings = [e.sensor.read() if r is None else r  # None: the env reads its own
                for e, r in zip(envs, readings, strict=True)]
    c = e0.system.constants
    ref = c.layout.reference
    power = np.array([r.power for r in readings], dtype=np.float64)
    clean = np.array([r.power_clean for r in readings])
    distance = np.array([r.distance[ref] for r in readings])
    emission = np.array([r.emission_angle[ref] for r in readings])
    for e, r in zip(envs, readings, strict=True):
        e.reading = r
    obs = power
    if e0.cfg.imu:
        nav = vehicles._reading
        encoder = per_element(math.remainder, nav.encoder, 2 * math.pi)
        obs = np.column_stack([power, nav.gyro[:, 2], nav.dvl[:, :2], encoder,
                               vehicles.sight.rate])
    space = e0.observation_space
    obs = np.minimum(np.maximum(obs, space.low), space.high)
    # share_of_achievable: min(1, clean / best), 0 where nothing is achievable
    best = _achievable(distance, emission, c, e0.peak_response)
    lit = best > 0
    share = np.divide(clean[:, ref], best, out=np.zeros(len(envs)), where=lit)
    reward = np.where(lit, np.where(share < 1.0, share, 1.0), 0.0)
    info = {"phi": np.array([r.phi for r in readings]),
            "phidot": np.array([r.phidot for r in readings]),
            "power_clean": clean,
            "time": np.array([e.k * e.dt for e in envs])}
    return obs, reward, info


def _achievable(distance, emission, c: LinkConstants, peak_response: float) -> np.ndarray:
    """:func:`~ledsim.radiometry.optics.achievable_power` [W] of N distances [m] and
    emission angles [rad], each as the single env computes it from one numpy scalar:
    there the distance is a 0-d array (numpy's ``exp`` and square, which its arrays
    share) and the cosine a numpy scalar, whose power is libm's ``pow``."""
    cos_t = np.maximum(np.cos(emission), 0.0)
    intensity = per_element(math.pow, cos_t, float(c.lambertian_order))
    return c.power_scale * np.exp(-c.attenuation * distance) / distance**2 \
        * intensity * peak_response
