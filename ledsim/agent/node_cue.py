"""Where the vehicle's navigation puts the node: the cue a pan-tilt head points at while
it cannot see the LED (a fly-by's node still out of its beam, a survey's lanes away
from it, a loss on the move), and the range and emission angle its filters' gain and
its supervisor's levels follow.

The node's position and the way its LED points are known (a surveyed node); the
vehicle's pose is its aided INS's. The LED's direction from the gimbal's hinge, in the
world frame (its bearing and elevation), has turned by :attr:`NodeView.change` since
the start, when the head looked at it. The head's supervisor works in encoder angles
that add the hull's own turn (an inertial frame, ``agent/pan_tilt.py``), so the cue
there is the start's angles plus that change.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class NodeView(NamedTuple):
    """What the navigation says of the node at a step.

    Attributes:
        change: how far the LED's bearing and elevation have turned since the start
            [rad] (2,).
        range: the LED's distance from the gimbal's hinge [m].
        emission_angle: the angle off the LED's axis at which it sees the hinge [rad].
    """

    change: np.ndarray
    range: float
    emission_angle: float


class NodeCue:
    """The LED as seen from a moving vehicle, by its navigation.

    Args:
        led: the node's LED, world frame [m] (3,).
        axis: its emission axis, world frame (3,) (unit).
        l_gimbal: the gimbal's hinge in the hull's frame [m] (3,).
        start: the navigation at the start (an
            :class:`~observer.navigation.ins.InsState`).
    """

    def __init__(self, led, axis, l_gimbal, start):
        self.led = np.asarray(led, dtype=float).copy()
        self.axis = np.asarray(axis, dtype=float).copy()
        self.l_gimbal = np.asarray(l_gimbal, dtype=float).reshape(3)
        self.start = self._direction(self._offset(start))
        self._last = 0.0  # the bearing's last turn: the turn is continuous

    def _offset(self, nav) -> np.ndarray:
        """The LED from the navigated hinge, world frame [m] (3,)."""
        return self.led - (np.asarray(nav.position) + np.asarray(nav.attitude) @ self.l_gimbal)

    @staticmethod
    def _direction(d: np.ndarray) -> np.ndarray:
        return np.array([math.atan2(d[1], d[0]), math.atan2(d[2], math.hypot(d[0], d[1]))])

    def at(self, nav) -> NodeView:
        """The node from the navigation ``nav``. The bearing's turn is unwrapped: a
        vehicle that circles the node turns it past pi, as the pan's encoder does."""
        d = self._offset(nav)
        turn = self._direction(d) - self.start
        turn[0] = self._last + math.remainder(turn[0] - self._last, 2.0 * math.pi)
        self._last = float(turn[0])
        r = float(np.linalg.norm(d))
        cos_t = float(-(d @ self.axis)) / max(r, 1e-9)
        return NodeView(turn, r, math.acos(min(1.0, max(-1.0, cos_t))))
