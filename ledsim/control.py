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
from .optics import photodiode_power, receiver_response


def intensity_maximum(constants: LinkConstants) -> float:
    """phi [rad] at which photodiode 1 receives the most power (the alignment target)."""
    phi = np.linspace(-0.5, 0.5, 100001)
    return float(phi[np.argmax(receiver_response(phi, constants.receiver))])


@dataclass
class AlignmentPD:
    """u = -kp (phi_hat - phi_ref) - kd phidot_hat  [rad/s^2]: drive phi to the peak.

    Attributes:
        phi_ref: target incidence angle [rad] (default: the intensity maximum).
        kp: position gain [1/s^2]; kd: rate gain [1/s] (critically damped at 3 rad/s).
    """

    phi_ref: float = 0.0
    kp: float = 9.0
    kd: float = 6.0

    def __call__(self, xhat: np.ndarray, t: float) -> float:
        return -self.kp * (xhat[0] - self.phi_ref) - self.kd * xhat[1]


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

    A photodiode's sample counts as a dropout when it reads below ``floor`` W although
    the estimate predicts more than twice that: light that should be there is gone, as
    when a body crosses the beam. Missing samples are then handled by each estimator's
    own policy (KKL holds its prediction; Kalman and particle filters skip the update).
    After ``max_hold`` seconds of continuous dropouts the gate opens again, so a wrong
    estimate cannot lock out the measurements for good.

    Args:
        constants: link constants (the floor defaults to 10% of the peak power).
        floor: power below which a sample may be a dropout [W].
        max_hold: longest continuous dropout accepted [s].
    """

    def __init__(self, constants: LinkConstants, floor: float | None = None,
                 max_hold: float = 1.0):
        peak = float(np.max(photodiode_power(
            constants.distance, constants.theta, np.linspace(-0.5, 0.5, 2001), constants)))
        self.floor = 0.1 * peak if floor is None else floor
        self.max_steps = int(round(max_hold / constants.Te))
        self.held = np.zeros(2, dtype=int)

    def reset(self) -> None:
        self.held[:] = 0

    def __call__(self, y: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        drop = (y < self.floor) & (predicted > 2 * self.floor) & (self.held < self.max_steps)
        self.held = np.where(drop, self.held + 1, 0)
        return np.where(drop, np.nan, y)
