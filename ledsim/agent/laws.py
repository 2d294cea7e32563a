"""Control laws: the paper's input functions, its rate damping, and the alignment loop.

Every law outputs the paper's input u, an angular acceleration of phi [rad/s^2], per
gimbal axis (:mod:`ledsim.agent.axes`: a float for the paper's one axis; over n axes the
estimate is (angles, rates) and u an array of n). The
closed-form model adds it as ``Te u``; in MuJoCo the physics adapter turns it into a motor
torque (``GimbalSystem.torque_for``), clipped at the torque limit. A scenario holds one
law as a template; :meth:`start` gives a fresh copy bound to the link's constants, so
stateful laws (the PI integral) never leak from one run into the next.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from ledsim.agent.axes import angles_rates, clip
from ledsim.constants import LinkConstants
from ledsim.radiometry.optics import receiver_response


class ControlLaw(Protocol):
    """``law(x_hat, t) -> u`` [rad/s^2], with ``start(constants)`` for a fresh copy."""

    def start(self, constants: LinkConstants) -> ControlLaw: ...

    def __call__(self, xhat: np.ndarray, t: float) -> float: ...

    #: The law points the receiver at the beam, so a lost link is worth a scan to find
    #: it again (False for excitations, whose input is the experiment).
    tracks_beam: bool


@functools.lru_cache(maxsize=64)  # every law start and re-seed asks for it
def intensity_maximum(constants: LinkConstants) -> float:
    """phi [rad] at which photodiode 1 receives the most power (the alignment target)."""
    phi = np.linspace(-0.5, 0.5, 100001)
    return float(phi[np.argmax(receiver_response(phi, constants.receiver))])


@functools.lru_cache(maxsize=64)
def receiver_peak(constants: LinkConstants) -> float:
    """g at the intensity maximum: photodiode 1's best response [-] (what the achievable
    power multiplies the transmitter gain by)."""
    return float(receiver_response(intensity_maximum(constants), constants.receiver))


@dataclass
class Excitation:
    """Open-loop input cos_amp cos(w t) + sin_amp sin(w t) [rad/s^2] (IF1, IF2).

    Attributes:
        cos_amp, sin_amp: amplitudes [rad/s^2] (arrays over the axes for several);
        angular_frequency: w [rad/s].
    """

    tracks_beam = False

    cos_amp: float = 0.0
    sin_amp: float = 0.0
    angular_frequency: float = 5.0

    def start(self, constants: LinkConstants) -> Excitation:
        return replace(self)

    def __call__(self, xhat: np.ndarray, t: float) -> float:
        w = self.angular_frequency
        return self.cos_amp * math.cos(w * t) + self.sin_amp * math.sin(w * t)



@dataclass
class PaperRateDamping:
    """The paper's closed loop: u = -gain * phidot_hat (gain 0.001 [1/s]), per axis."""

    tracks_beam = False

    gain: float = 0.001

    def start(self, constants: LinkConstants) -> PaperRateDamping:
        return replace(self)

    def __call__(self, xhat: np.ndarray, t: float) -> float:
        return -self.gain * angles_rates(xhat)[1]



@dataclass
class AlignmentPID:
    """Cascade alignment controller, output u [rad/s^2].

    Outer loop: a rate command ``clip(-bandwidth (phi_hat - phi_ref), +-rate_max)`` that
    slews phi towards the intensity peak no faster than ``rate_max``, which keeps the
    motion inside the observers' training domain (|phidot| <= 0.5 rad/s). Inner loop: PI
    on the rate error, ``u = -kv r - ki int(r)``, ``r = phidot_hat - rate_cmd``; its
    integral rejects steady torques such as a water current on the gimbal housing.
    Over several axes each has its own loop (``phi_ref`` one target per axis, or one
    for all), and the integral is an array. The estimate is clipped to the domain and
    u to +-u_max, so a wrong estimate cannot spin the gimbal away.

    Attributes:
        phi_ref: target incidence angle [rad]; None = the intensity maximum.
        bandwidth: outer-loop bandwidth [rad/s]; rate_max: slew-rate limit [rad/s].
        kv [1/s], ki [1/s^2]: inner PI gains; Te: control period [s] (None: the link's).
        u_max: command limit [rad/s^2]; i_max: clamp of the integral [rad/s].
        domain: half-widths of the estimate's clip (phi [rad], phidot [rad/s]).
    """

    tracks_beam = True

    phi_ref: float | None = None
    bandwidth: float = 3.0
    rate_max: float = 0.3
    kv: float = 12.0
    ki: float = 36.0
    Te: float | None = None
    u_max: float = 200.0
    i_max: float = 3.0
    domain: tuple[float, float] = (0.5, 0.5)

    def __post_init__(self):
        self.integral = 0.0

    def start(self, constants: LinkConstants) -> AlignmentPID:
        return replace(self, Te=constants.Te if self.Te is None else self.Te,
                       phi_ref=intensity_maximum(constants) if self.phi_ref is None
                       else self.phi_ref)

    def __call__(self, xhat: np.ndarray, t: float) -> float:
        phi, rate = angles_rates(xhat)
        phi = clip(phi, -self.domain[0], self.domain[0])
        rate = clip(rate, -self.domain[1], self.domain[1])
        cmd = clip(-self.bandwidth * (phi - self.phi_ref), -self.rate_max, self.rate_max)
        r = rate - cmd
        self.integral = clip(self.integral + r * self.Te, -self.i_max, self.i_max)
        u = -self.kv * r - self.ki * self.integral
        return clip(u, -self.u_max, self.u_max)

    def take_over(self, u: float) -> None:
        """Start from the input ``u`` [rad/s^2] the motor gave so far (the warm-up hold's
        torque against a steady load, such as the water on the gimbal housing): the
        integral takes it over, so the hand-over does not drop the load."""
        self.integral = clip(-u / self.ki, -self.i_max, self.i_max)
