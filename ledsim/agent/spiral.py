"""Finding the beam in two dimensions: a spiral scan of a pan-tilt head.

Where the beam is outside the field of view, a one-axis gimbal sweeps back and forth
(:class:`~ledsim.agent.acquisition.AcquisitionScan`); a two-axis one covers the sky
around where it looks with an Archimedean spiral, as pointing-acquisition-tracking
terminals do: the radius grows by ``pitch`` every turn (less than the field of view, so
that no direction falls between two turns), at a constant speed along the path. Each
axis follows its share of the spiral's reference with the scan's cascade
(:func:`~ledsim.agent.acquisition.follow`), so the command is the input u per
axis (q'' = -u, as every axis turns). The caller stops the scan when the powers show the
beam and hands over to the estimator.
"""

from __future__ import annotations

import math

import numpy as np

from ledsim.agent.acquisition import follow


class SpiralScan:
    """An Archimedean spiral of the encoder angles of two axes around a centre.

    Args:
        Te: the control period [s].
        pitch: growth of the radius every turn [rad] (under the field of view).
        speed: the speed along the path [rad/s].
        gains: the cascade's (kp [1/s^2], kd [1/s]), per axis.
        max_radius: the spiral's largest radius [rad]; past it, it starts again.
    """

    def __init__(self, Te: float, pitch: float = 0.3, speed: float = 1.0,
                 gains: tuple[float, float] = (100.0, 20.0), max_radius: float = math.pi):
        self.Te, self.pitch, self.speed = Te, pitch, speed
        self.gains, self.max_radius = gains, max_radius
        self.active = False
        self.centre = np.zeros(2)
        self.theta = 0.0

    def start(self, centre) -> None:
        """Spiral around the encoder angles ``centre`` [rad], shape (2,)."""
        self.centre = np.asarray(centre, dtype=float).copy()
        self.theta = 0.0
        self.active = True

    def stop(self) -> None:
        self.active = False

    def reference(self) -> tuple[np.ndarray, np.ndarray]:
        """The spiral's encoder angles [rad] and rates [rad/s] now, shape (2,) each."""
        b = self.pitch / (2.0 * math.pi)  # r = b theta
        r = b * self.theta
        c, s = math.cos(self.theta), math.sin(self.theta)
        dtheta = self.speed / math.hypot(r, b)  # |d(r e_theta)/d theta| = sqrt(r^2 + b^2)
        angle = self.centre + r * np.array([c, s])
        rate = dtheta * np.array([b * c - r * s, b * s + r * c])
        return angle, rate

    def command(self, q, qdot) -> np.ndarray:
        """The input u = angle'' per axis [rad/s^2] (q'' = -u) that follows the spiral
        from encoder angles ``q`` [rad] and rates ``qdot`` [rad/s]; advances by Te."""
        ref, feed = self.reference()
        u = follow(np.asarray(q), np.asarray(qdot), ref, feed, self.gains, 1.5 * self.speed)
        b = self.pitch / (2.0 * math.pi)
        self.theta += self.speed / math.hypot(b * self.theta, b) * self.Te
        if b * self.theta > self.max_radius:
            self.theta = 0.0
        return u
