"""LED link optics: paper eqs. (pow-d-theta-phi) and (modified-gaussian2).

All angles in rad, distances in m, powers in W. Functions broadcast over arrays.
"""

from __future__ import annotations

import numpy as np

from .config import LinkConstants, ReceiverResponse


def receiver_response(phi, r: ReceiverResponse) -> np.ndarray:
    """g(phi): dimensionless photodiode response at incidence angle ``phi`` [rad]."""
    phi = np.asarray(phi, dtype=float)
    return (r.a1 * np.exp(-(((phi - r.b1) / r.c1) ** 2))
            + r.a2 * np.exp(-(((phi + r.b2) / r.c2) ** 2)))


def receiver_response_derivative(phi, r: ReceiverResponse) -> np.ndarray:
    """dg/dphi [1/rad]."""
    phi = np.asarray(phi, dtype=float)
    e1 = r.a1 * np.exp(-(((phi - r.b1) / r.c1) ** 2))
    e2 = r.a2 * np.exp(-(((phi + r.b2) / r.c2) ** 2))
    return -2 * (phi - r.b1) / r.c1**2 * e1 - 2 * (phi + r.b2) / r.c2**2 * e2


def led_intensity(theta, c: LinkConstants) -> np.ndarray:
    """I~(theta): Lambertian angular intensity of the LED, 1 on axis, 0 behind it."""
    cos_t = np.clip(np.cos(np.asarray(theta, dtype=float)), 0.0, None)
    return cos_t ** c.lambertian_order


def transmitter_gain(d, theta, c: LinkConstants) -> np.ndarray:
    """The transmitter part a exp(-b d) / d^2 * I~(theta) of eq. (pow-d-theta-phi) [W]."""
    d = np.asarray(d, dtype=float)
    return c.power_scale * np.exp(-c.attenuation * d) / d**2 * led_intensity(theta, c)


def photodiode_power(d, theta, incidence_angle, c: LinkConstants) -> np.ndarray:
    """Received optical power P_d(d, theta, phi) [W], eq. (pow-d-theta-phi)."""
    return transmitter_gain(d, theta, c) * receiver_response(incidence_angle, c.receiver)


def peak_power(c: LinkConstants) -> float:
    """Largest power one photodiode can see at the configured distance and theta [W]."""
    phi = np.linspace(-np.pi / 2, np.pi / 2, 20001)
    return float(np.max(photodiode_power(c.distance, c.theta, phi, c)))
