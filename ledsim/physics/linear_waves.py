"""Linear (Airy) wave theory: a regular wave's surface, and its water's velocity and
acceleration at any point, in finite or deep water.

A wave of height H (crest to trough), period T, travelling along ``heading`` beta over
water of depth h has amplitude a = H / 2, angular frequency w = 2 pi / T and the
wavenumber k of the dispersion relation w^2 = g k tanh(k h). At a point at depth s
below the still surface, with xi its distance along beta and theta = k xi - w t:

    eta   = a cos(theta)                                   the surface's elevation [m]
    u     = a w C(s) cos(theta)        along beta          [m/s]
    w     = a w S(s) sin(theta)        up                  [m/s]
    du/dt = a w^2 C(s) sin(theta),   dw/dt = -a w^2 S(s) cos(theta)      [m/s^2]

    C(s) = cosh(k (h - s)) / sinh(k h),   S(s) = sinh(k (h - s)) / sinh(k h)

which both become exp(-k s) in deep water (h -> infinity). Sources: Dean and Dalrymple,
*Water Wave Mechanics for Engineers and Scientists* (1991), ch. 3-4; DNV-RP-C205 (2021),
sec. 3.2. The water particles move on ellipses (circles in deep water) of semi-axes
a C(s) and a S(s). The convective terms of the acceleration are second order in the
wave's steepness and left out, as linear theory does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ledsim.constants import GRAVITY


def wavenumber(period: float, water_depth: float = math.inf) -> float:
    """k [rad/m] of a wave of ``period`` [s] over ``water_depth`` [m] (inf: deep water),
    from w^2 = g k tanh(k h) (Newton's method from the deep-water k)."""
    w = 2.0 * math.pi / period
    k = w * w / GRAVITY
    if math.isinf(water_depth):
        return k
    k = max(k, w / math.sqrt(GRAVITY * water_depth))  # the shallow-water k is a lower bound
    for _ in range(50):
        t = math.tanh(k * water_depth)
        f = GRAVITY * k * t - w * w
        df = GRAVITY * (t + k * water_depth * (1.0 - t * t))
        step = f / df
        k -= step
        if abs(step) < 1e-14 * k:
            break
    return k


@dataclass(frozen=True)
class RegularWave:
    """One linear wave (see the module docstring).

    Attributes:
        height: H, crest to trough [m].
        period: T [s].
        heading: the direction it travels, in the horizontal plane [rad] (0 = world +x).
        water_depth: h, the sea's depth under the still surface [m] (inf: deep water).
    """

    height: float
    period: float
    heading: float = 0.0
    water_depth: float = math.inf

    @property
    def omega(self) -> float:
        """w = 2 pi / T [rad/s]."""
        return 2.0 * math.pi / self.period

    @property
    def k(self) -> float:
        """The wavenumber [rad/m]."""
        return wavenumber(self.period, self.water_depth)

    @property
    def wavelength(self) -> float:
        """2 pi / k [m]."""
        return 2.0 * math.pi / self.k

    def decay(self, depth) -> tuple[np.ndarray, np.ndarray]:
        """(C, S) at ``depth`` s below the still surface [m] (any shape): the horizontal
        and vertical motion's share of the surface's."""
        s = np.asarray(depth, dtype=float)
        k, h = self.k, self.water_depth
        if math.isinf(h):
            e = np.exp(-k * s)
            return e, e
        sh = math.sinh(k * h)
        return np.cosh(k * (h - s)) / sh, np.sinh(k * (h - s)) / sh

    def phase(self, points, t: float) -> np.ndarray:
        """theta = k xi - w t at ``points`` (..., 3) (world frame, only x, y used) [rad]."""
        p = np.asarray(points, dtype=float)
        xi = p[..., 0] * math.cos(self.heading) + p[..., 1] * math.sin(self.heading)
        return self.k * xi - self.omega * t

    def elevation(self, points, t: float) -> np.ndarray:
        """eta, the surface's height above its still level at ``points``' x, y [m]."""
        return 0.5 * self.height * np.cos(self.phase(points, t))

    def kinematics(self, points, depth, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The water's velocity [m/s] and acceleration [m/s^2], world frame (..., 3), at
        ``points`` (..., 3) whose depths below the still surface are ``depth`` (...)."""
        a, w = 0.5 * self.height, self.omega
        theta = self.phase(points, t)
        c, s = self.decay(depth)
        cos, sin = np.cos(theta), np.sin(theta)
        bx, by = math.cos(self.heading), math.sin(self.heading)
        horizontal, vertical = a * w * c * cos, a * w * s * sin
        ah, av = a * w * w * c * sin, -a * w * w * s * cos
        vel = np.stack([horizontal * bx, horizontal * by, vertical], axis=-1)
        acc = np.stack([ah * bx, ah * by, av], axis=-1)
        return vel, acc
