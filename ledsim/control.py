"""Alignment controllers and the handling of occluded samples.

Control laws output the paper's input u (angular acceleration of phi, rad/s^2); the
physics adapter turns it into a motor torque (``GimbalSystem.torque_for``), clipped at
the torque limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .config import LinkConstants
from .optics import peak_power, receiver_response


def intensity_maximum(constants: LinkConstants) -> float:
    """phi [rad] at which photodiode 1 receives the most power (the alignment target)."""
    phi = np.linspace(-0.5, 0.5, 100001)
    return float(phi[np.argmax(receiver_response(phi, constants.receiver))])


@dataclass
class AlignmentPID:
    """Cascade alignment controller, output u [rad/s^2].

    Outer loop: a rate command ``clip(-omega (phi_hat - phi_ref), +-rate_max)`` that
    slews phi towards the intensity peak no faster than ``rate_max``, which keeps the
    motion inside the observers' training domain (|phidot| <= 0.5 rad/s). Inner loop: PI
    on the rate error, ``u = -kv r - ki int(r)``, ``r = phidot_hat - rate_cmd``; its
    integral rejects steady torques such as a water current on the gimbal housing.
    The estimate is clipped to the domain and u to +-u_max, so a wrong estimate cannot
    spin the gimbal away; no command is given during the first ``warmup`` seconds, while
    the estimators forget their initial guess.

    Attributes:
        phi_ref: target incidence angle [rad] (the intensity maximum).
        omega: outer-loop bandwidth [rad/s]; rate_max: slew-rate limit [rad/s].
        kv [1/s], ki [1/s^2]: inner PI gains; Te: control period [s].
        u_max: command limit [rad/s^2]; i_max: clamp of the integral [rad/s];
        warmup: time without command at the start [s].
    """

    phi_ref: float = 0.0
    omega: float = 3.0
    rate_max: float = 0.3
    kv: float = 12.0
    ki: float = 36.0
    Te: float = 0.01
    u_max: float = 200.0
    i_max: float = 0.1
    warmup: float = 1.0
    domain: tuple[float, float] = (0.5, 0.5)

    def __post_init__(self):
        self.integral = 0.0

    def __call__(self, xhat: np.ndarray, t: float) -> float:
        if t < self.warmup:  # the estimator converges; the loop holds the encoder angle
            return 0.0
        phi = min(max(xhat[0], -self.domain[0]), self.domain[0])
        rate = min(max(xhat[1], -self.domain[1]), self.domain[1])
        cmd = min(max(-self.omega * (phi - self.phi_ref), -self.rate_max), self.rate_max)
        r = rate - cmd
        self.integral = min(max(self.integral + r * self.Te, -self.i_max), self.i_max)
        u = -self.kv * r - self.ki * self.integral
        return min(max(u, -self.u_max), self.u_max)


@dataclass
class PaperRateDamping:
    """The paper's closed loop: u = -gain * phidot_hat (gain 0.001)."""

    gain: float = 0.001

    def __call__(self, xhat: np.ndarray, t: float) -> float:
        return -self.gain * xhat[1]


@dataclass
class Excitation:
    """Open-loop input cos_amp cos(omega t) + sin_amp sin(omega t) [rad/s^2] (IF1, IF2)."""

    cos_amp: float = 0.0
    sin_amp: float = 0.0
    omega: float = 5.0

    def __call__(self, xhat: np.ndarray, t: float) -> float:
        return self.cos_amp * math.cos(self.omega * t) + self.sin_amp * math.sin(self.omega * t)


class DropoutGate:
    """Marks occluded samples as missing (NaN) before they reach any estimator.

    A body crossing the beam cuts the light within a few milliseconds, while turning the
    gimbal dims it smoothly. A photodiode's sample therefore counts as a dropout when it
    falls below ``floor`` W while the recent level of that photodiode (an exponential
    average of its accepted samples) was above twice the floor, and it stays one while
    the power stays below the floor. Missing samples are then handled by each
    estimator's own policy (KKL holds its prediction; Kalman and particle filters skip
    the update). After ``max_hold`` seconds the gate gives up and passes the samples
    again, so a lasting loss of light is seen as what it is.

    The gate looks only at the measurements, so every estimator gets the same input.

    Args:
        constants: link constants (the floor defaults to 10% of the peak power).
        floor: power below which a sample may be a dropout [W].
        max_hold: longest dropout bridged [s].
        smoothing: weight of a new sample in the recent level.
    """

    def __init__(self, constants: LinkConstants, floor: float | None = None,
                 max_hold: float = 1.0, smoothing: float = 0.2):
        self.floor = 0.1 * peak_power(constants) if floor is None else floor
        self.max_steps = int(round(max_hold / constants.Te))
        self.smoothing = smoothing
        self.reset()

    def reset(self) -> None:
        self.held = np.zeros(2, dtype=int)
        self.level = None

    def __call__(self, y: np.ndarray) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        if self.level is None:
            self.level = y.copy()
        low = y < self.floor
        start = low & (self.held == 0) & (self.level > 2 * self.floor)
        drop = (start | (low & (self.held > 0))) & (self.held < self.max_steps)
        self.held = np.where(drop, self.held + 1, 0)
        a = self.smoothing
        self.level = np.where(drop, self.level, (1 - a) * self.level + a * y)
        return np.where(drop, np.nan, y)
