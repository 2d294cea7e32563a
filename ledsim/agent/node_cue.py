"""Where the vehicle's navigation puts the node: the cue a pan-tilt head points at while
it cannot see the LED (a fly-by's node still out of its beam, a survey's lanes away
from it, a loss on the move), and the range and emission angle its filters' gain and
its supervisor's levels follow.

The vehicle's pose is its aided INS's. The node's position is its belief: the surveyed
position, or, where that is off (``node_error``), an estimate it improves from where
its head finds the LED. Each step the head holds the LED it looks along a ray from the
navigated hinge; the rays from along the path cross at the node (bearing-only
localisation), and the belief is their least-squares point, weighted against the prior
(:meth:`NodeCue.learn`). The way the LED points is known (the node's survey).

The head started looking at the LED (its encoders' home). The LED's direction from the
gimbal's hinge, in the world frame (bearing and elevation), has turned by
:attr:`NodeView.change` since then, as the belief puts it; the head's supervisor works in
encoder angles that add the hull's own turn (an inertial frame, ``agent/pan_tilt.py``),
so the cue there is the home plus that change.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

#: The angular error of a look along which the head holds the LED [rad] (its fix's and
#: estimate's, 0.01 rad at the edge of the beam), which weighs each ray; and how many
#: looks make one ray (successive looks share their error: one ray each half second).
LOOK_STD, LOOKS_PER_RAY = 0.01, 50
#: A ray that misses the belief by more than this many standard deviations (the
#: belief's and the ray's) is not the LED's (a look at a beam's edge) [-].
RAY_GATE = 3.0


class NodeView(NamedTuple):
    """What the navigation says of the node at a step.

    Attributes:
        change: how far the LED's bearing and elevation have turned since the start
            [rad] (2,).
        range: the LED's distance from the gimbal's hinge [m].
        emission_angle: the angle off the LED's axis at which it sees the hinge [rad].
        spread: three standard deviations of the belief's direction [rad] (0: the
            node's position is known).
    """

    change: np.ndarray
    range: float
    emission_angle: float
    spread: float = 0.0


class NodeCue:
    """The LED as seen from a moving vehicle, by its navigation and its belief of where
    the node is.

    Args:
        led: the node's LED, world frame [m] (3,) (where the head looked at the start).
        axis: its emission axis, world frame (3,) (unit).
        l_gimbal: the gimbal's hinge in the hull's frame [m] (3,).
        start: the navigation at the start (an
            :class:`~observer.navigation.ins.InsState`).
        error: the belief's error [m] per axis (0: the node is where it is).
        rng: draws the belief's error (a :class:`numpy.random.Generator`).
    """

    def __init__(self, led, axis, l_gimbal, start, error: float = 0.0, rng=None):
        led = np.asarray(led, dtype=float)
        self.axis = np.asarray(axis, dtype=float).copy()
        self.l_gimbal = np.asarray(l_gimbal, dtype=float).reshape(3)
        d = led - self._hinge(start)
        self.start = self._direction(d)
        #: the true range [m] and emission angle [rad] at the start, which the head's
        #: model was calibrated at (as the start's look is the encoders' home)
        self.reference = self._range_angle(d)
        self._last = 0.0  # the bearing's last turn: the turn is continuous
        self.error = float(error)
        self.led = led.copy()  # the belief
        if self.error > 0:
            self.led = led + (rng or np.random.default_rng()).normal(0.0, self.error, 3)
            self._info = np.eye(3) / self.error**2  # the belief's information [1/m^2]
            self._vector = self._info @ self.led
        self._looks = 0

    def _hinge(self, nav) -> np.ndarray:
        return np.asarray(nav.position) + np.asarray(nav.attitude) @ self.l_gimbal

    def _range_angle(self, d: np.ndarray) -> tuple[float, float]:
        """The range [m] of the LED offset ``d`` (from the hinge) and the angle off the
        LED's axis at which it sees the hinge [rad]."""
        r = float(np.linalg.norm(d))
        cos_t = float(-(d @ self.axis)) / max(r, 1e-9)
        return r, math.acos(min(1.0, max(-1.0, cos_t)))

    @staticmethod
    def _direction(d: np.ndarray) -> np.ndarray:
        return np.array([math.atan2(d[1], d[0]), math.atan2(d[2], math.hypot(d[0], d[1]))])

    def at(self, nav) -> NodeView:
        """The node from the navigation ``nav``. The bearing's turn is unwrapped: a
        vehicle that circles the node turns it past pi, as the pan's encoder does."""
        d = self.led - self._hinge(nav)
        turn = self._direction(d) - self.start
        turn[0] = self._last + math.remainder(turn[0] - self._last, 2.0 * math.pi)
        self._last = float(turn[0])
        r, emission = self._range_angle(d)
        spread = 0.0
        if self.error > 0:  # the belief's largest standard deviation, seen from here
            sigma = math.sqrt(float(np.linalg.eigvalsh(np.linalg.inv(self._info))[-1]))
            spread = min(3.0 * sigma / max(r, 1.0), math.pi)
        return NodeView(turn, r, emission, spread)

    def learn(self, nav, change) -> None:
        """The head holds the LED looking ``change`` [rad] (bearing, elevation) turned
        from the start's look, from the navigation ``nav``: a ray from the hinge the
        node lies on, weighed by :data:`LOOK_STD` at the belief's range. Without a
        belief's error, nothing to learn."""
        if self.error <= 0:
            return
        self._looks += 1
        if self._looks % LOOKS_PER_RAY:
            return
        bearing, elevation = self.start + np.asarray(change, dtype=float)
        u = np.array([math.cos(elevation) * math.cos(bearing),
                      math.cos(elevation) * math.sin(bearing), math.sin(elevation)])
        origin = self._hinge(nav)
        r = max(float(np.linalg.norm(self.led - origin)), 1.0)
        project = np.eye(3) - np.outer(u, u)
        miss = float(np.linalg.norm(project @ (self.led - origin)))
        belief = float(np.linalg.eigvalsh(np.linalg.inv(self._info))[-1])
        if miss > RAY_GATE * math.sqrt(belief + (r * LOOK_STD) ** 2):
            return
        across = project / (r * LOOK_STD) ** 2
        self._info += across
        self._vector += across @ origin
        self.led = np.linalg.solve(self._info, self._vector)
