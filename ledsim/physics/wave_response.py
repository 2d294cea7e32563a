"""A free hull's response to a regular wave by strip theory, beside linear theory's
water orbit (``scripts/sea_response.py``, ``tests/test_sea.py``)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ledsim.constants import GRAVITY


class WaveResponse(NamedTuple):
    """The hull's amplitudes at the wave's frequency.

    Attributes:
        surge, sway, heave: over the water's orbit radius (H / 2) exp(-k z) [-] (1: the
            hull moves with the water).
        pitch: the pitch amplitude [rad].
        slope: the wave's slope k (H / 2) exp(-k z) at the hull's depth [rad].
    """

    surge: float
    sway: float
    heave: float
    pitch: float
    slope: float


def free_hull_response(period: float, depth: float, heading: float, height: float = 1.0,
                       seconds: float = 60.0, link: str = "luma") -> WaveResponse:
    """The neutrally buoyant hull, free (no station keeping, thrusters idle), in a
    regular deep-water wave of ``height`` [m] and ``period`` [s] from ``heading``
    [rad], ``depth`` [m] down, on ``link``'s world (strip theory is a physical link's
    default): each amplitude from a least-squares sine with a drift over the last two
    thirds of ``seconds``."""
    from ledsim.physics.disturbances import parse_disturbance
    from ledsim.physics.scene import WorldConfig
    from ledsim.physics.tick import prepare
    from ledsim.physics.world import LinkWorld
    from ledsim.physics.world_rows import WorldRows
    from ledsim.radiometry.link_presets import link_constants

    c = link_constants(link, 30.0)
    world = LinkWorld(WorldConfig(constants=c, depth=depth))
    waves = parse_disturbance(f"waves:height={height:g},period={period:g},"
                              f"heading={heading:.6f},hold=0")
    n = int(round(seconds / c.Te))
    pos, pitch = np.empty((n, 3)), np.empty(n)
    prepare(world, [waves], 0.0)
    rows = WorldRows([world])  # the world as a row of one: the one tick
    rows.start(None, [[waves]], [None])
    for k in range(n):
        rows.tick((k + 1) * c.Te, torques=(0.0,))
        pos[k] = world.hull_pos
        pitch[k] = -math.asin(max(-1.0, min(1.0, float(world.hull_rotation[2, 0]))))
    t = np.arange(1, n + 1) * c.Te
    w = 2 * math.pi / period
    design = np.stack([np.cos(w * t), np.sin(w * t), np.ones_like(t), t], axis=1)[n // 3:]

    def amplitude(y):
        coef, *_ = np.linalg.lstsq(design, y[n // 3:], rcond=None)
        return math.hypot(coef[0], coef[1])

    k = w * w / GRAVITY
    orbit = 0.5 * height * math.exp(-k * depth)
    surge, sway, heave = (amplitude(pos[:, i]) / orbit for i in range(3))
    return WaveResponse(surge, sway, heave, amplitude(pitch), k * orbit)
