"""The field's pointing baselines on one photodiode, which must scan to see a direction.

Both run on the data detector's power alone (the other photodiodes are treated as
missing) and sweep the boresight around where they believe the LED is: a circle of
radius :func:`dip_radius` (the beam's power there is ``1 - dip`` of its peak) at
``frequency`` [Hz]. The scan is in what they report: the estimate plus the circle's
offset and rate, so a control law that drives the reported misalignment to zero holds
the LED on that circle. Their own estimate (:attr:`belief`) is what they think the
misalignment is.

- :class:`ScanningEKF`: Solanki, Al-Rubaiai and Tan (IEEE/ASME Trans. Mechatronics
  2018), an EKF on the single photodiode's power model, with the scan giving the motion
  that makes the direction observable.
- :class:`ExtremumSeeking`: the classic model-free hill climb. It never evaluates the
  power model: the power's ripple over one scan period, demodulated by the head's own
  motion (which the input it is told carries, as an encoder would), gives the slope,
  and a second-order loop (an angle and its rate) climbs it.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from observer.baselines.ekf import ExtendedKalmanFilter
from observer.estimator import Estimator
from observer.system import DiscreteSystem

#: The power the scan gives up at its radius, over the peak [-] (a 0.09 dB loss).
DIP = 0.02
#: The scan's frequency [Hz] (3.1 rad/s, at the alignment loop's 3 rad/s outer
#: bandwidth: the head follows the circle, smaller and later, which both baselines see
#: through the input they are told).
FREQUENCY = 0.5


def dip_radius(system: DiscreteSystem, detector: int, dip: float = DIP) -> float:
    """The angle off the boresight [rad] (on the first axis) at which the detector's
    model power is ``1 - dip`` of its peak: the scan's radius, as a designer tunes it."""
    peak = float(system.h(np.zeros(system.n_state))[detector])
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        x = np.r_[mid, np.zeros(system.n_state - 1)]  # off on the first axis
        lo, hi = (mid, hi) if system.h(x)[detector] > (1.0 - dip) * peak else (lo, mid)
    return 0.5 * (lo + hi)


class CircularScan:
    """The scan's offset from the estimate: a circle of ``radius`` [rad] at
    ``frequency`` [Hz] over the first two axes (on one axis, a sine)."""

    def __init__(self, n_axes: int, radius: float, frequency: float, Te: float):
        self.n, self.radius, self.w, self.Te = n_axes, float(radius), 2 * math.pi * frequency, Te
        self.k = 0  # the step count

    def __call__(self) -> tuple[np.ndarray, np.ndarray]:
        """The offset [rad] and its rate [rad/s] now, per axis."""
        wt = self.w * self.k * self.Te
        a, w = self.radius, self.w
        off, rate = np.zeros(self.n), np.zeros(self.n)
        off[0], rate[0] = a * math.cos(wt), -a * w * math.sin(wt)
        if self.n > 1:
            off[1], rate[1] = a * math.sin(wt), a * w * math.cos(wt)
        return off, rate

    def around(self, x: np.ndarray) -> np.ndarray:
        off, rate = self()
        return np.r_[x[:self.n] + off, x[self.n:] + rate]


class ScanningEKF(ExtendedKalmanFilter):
    """Solanki et al.'s scanning EKF: :class:`ExtendedKalmanFilter` fed only
    ``detector``'s power, reporting its estimate plus the scan's offset.

    Args:
        system: the plant's model (f, and h of which ``detector``'s power is used).
        detector: the photodiode's index among the powers.
        radius: the scan's radius [rad] (default: :func:`dip_radius`).
        frequency: the scan's [Hz].
        restart_std: the angle's and the rate's standard deviations [rad], [rad/s] a
            restart from a given state starts with (a fix's, not the whole domain's: on
            one photodiode a wide prior cannot tell the two sides of the peak apart).
    """

    name = "scan-ekf"

    def __init__(self, system: DiscreteSystem, detector: int, radius: float | None = None,
                 frequency: float = FREQUENCY, restart_std: tuple = (0.02, 0.1), **kwargs):
        self.detector = int(detector)
        n = system.n_state // 2
        self.scan = CircularScan(n, dip_radius(system, detector) if radius is None
                                 else radius, frequency, system.Te)
        self._restart = np.diag(np.repeat(np.square(restart_std), n))
        super().__init__(system, **kwargs)

    def reset(self, x0=None, covariance=None) -> None:
        if x0 is not None and covariance is None:
            covariance = self._restart
        super().reset(x0, covariance)

    @property
    def belief(self) -> np.ndarray:
        """The estimate without the scan's offset."""
        return self.x.copy()

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        one = np.full_like(y, np.nan)
        one[self.detector] = y[self.detector]
        return self.scan.around(super().update(one))

    def predict(self, u) -> None:
        super().predict(u)
        self.scan.k += 1


class _Window:
    """A running mean over the last ``n`` values (arrays or floats)."""

    def __init__(self, n: int):
        self.values: deque = deque(maxlen=n)
        self.total = 0.0

    def add(self, v):
        if len(self.values) == self.values.maxlen:
            self.total = self.total - self.values[0]
        self.values.append(v)
        self.total = self.total + v
        return self.total / len(self.values)

    @property
    def full(self) -> bool:
        return len(self.values) == self.values.maxlen


class ExtremumSeeking(Estimator):
    """Model-free extremum seeking on ``detector``'s power, with a circular dither.

    Each step the log of the power and the head's angle (its estimate, carried by the
    model's f under the input it is told: the head's own motion, as an encoder would
    tell it) pass a high-pass of one scan period, which turns a drift (the range on a
    fly-by, the hull's heave) into a constant. Over one period, the least-squares slope
    of the log power's ripple on the head's offset (both axes at once: the tilt and
    the pan follow the circle with different lags, an ellipse) is the gradient of the
    log power, -m / w^2 at a misalignment m for a beam of width w (the beam whose power
    dips by ``dip`` at ``radius``: the gain a designer tunes). The misalignment steers a
    second-order loop of natural time ``time_constant`` [s]: the angle and the LED's
    turn rate (so a steady turn is followed without lag).
    """

    name = "es"

    def __init__(self, system: DiscreteSystem, detector: int, radius: float | None = None,
                 frequency: float = FREQUENCY, time_constant: float = 4.0, dip: float = DIP):
        super().__init__(system)
        self.detector = int(detector)
        self.n = system.n_state // 2
        radius = dip_radius(system, detector, dip) if radius is None else radius
        self.scan = CircularScan(self.n, radius, frequency, system.Te)
        self.width2 = radius * radius / (2.0 * dip)  # w^2 [rad^2]
        self.period = max(2, int(round(1.0 / (frequency * system.Te))))
        self.high_pass = system.Te * frequency  # the high-pass's step over its time
        self.tau = float(time_constant)
        self.reset()

    def reset(self, x0=None, covariance=None) -> None:
        self.x = self.initial_guess(x0)  # the head's motion (f), the LED held still
        self.shift = np.zeros(self.n)  # the climb's correction to the angle [rad]
        self.turn = np.zeros(self.n)  # the LED's turn rate it has learnt [rad/s]
        self._slow = None  # the high-passes' low parts: (log power, angle)
        self.ripple, self.offset, self.centre = (_Window(self.period) for _ in range(3))
        self.cross, self.spread = _Window(self.period), _Window(self.period)
        self.report = self.belief

    @property
    def belief(self) -> np.ndarray:
        """The estimate without the scan's offset."""
        return np.r_[self.x[:self.n] + self.shift, self.x[self.n:] + self.turn]

    def update(self, y) -> np.ndarray:
        J = float(np.asarray(y, dtype=float)[self.detector])
        if math.isfinite(J) and J > 0:
            lj, angle = math.log(J), self.x[:self.n] + self.shift
            if self._slow is None:
                self._slow = (lj, angle.copy())
            a = self.high_pass
            slow_j, slow_a = self._slow
            slow_j, slow_a = slow_j + a * (lj - slow_j), slow_a + a * (angle - slow_a)
            self._slow = (slow_j, slow_a)
            r, o = lj - slow_j, angle - slow_a
            mean_r, mean_o = self.ripple.add(r), self.offset.add(o)
            centre = self.centre.add(angle)
            cross = self.cross.add(r * o) - mean_r * mean_o
            spread = self.spread.add(np.outer(o, o)) - np.outer(mean_o, mean_o)
            if self.cross.full:
                try:
                    grad = np.linalg.solve(spread, cross)
                except np.linalg.LinAlgError:  # no scan yet (a head held still)
                    grad = None
                if grad is not None and np.all(np.isfinite(grad)):
                    # the misalignment of the window's centre, less what the estimate holds
                    e = -self.width2 * grad - centre
                    Te, tau = self.system.Te, self.tau
                    self.turn = self.turn + e * Te / (tau * tau)
                    self.shift = self.shift + 2.0 * e * Te / tau
        self.report = self.scan.around(self.belief)
        return self.report.copy()

    def predict(self, u) -> None:
        self.x = np.asarray(self.system.f(self.x, u), dtype=float)
        self.shift = self.shift + self.turn * self.system.Te
        self.scan.k += 1
