"""The gain-scheduled KKL's design (the family of filter banks its maps are learned
for) and its gain schedule (:mod:`observer.kkl.scheduled`)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from observer.exceptions import ObserverError


@dataclass(frozen=True)
class ScheduledDesign:
    """The family of filter banks and the range the maps are learned on.

    At gain w each output's bank has ``n_rates`` rates, geometric from ``slowest x w``
    to ``fastest`` [1/s]: the slow filters slow down with w (longer averaging) while the
    fastest stays, which keeps the state observable from z at every gain (scaling every
    rate alike lost it: at w = 0.05 the decoder's error was 7e-2 rad).

    Attributes:
        slowest: the slowest rate at w = 1 [1/s].
        fastest: the fastest rate, at every w [1/s].
        n_rates: filters per output.
        n_output: outputs, each filtered by its own bank (q = n_output x n_rates).
        w_range: gains w [-] the maps are learned for (low, high).
        noise_range: measurement noise over the nominal [-] the decoder is learned for.
        lock_box: half-widths of the locked decoder's prior over the domain's [-]:
            once the estimate is near the operating point, a decoder that knows it is
            used, as a Kalman filter's shrunken covariance does.
        name: label in tables.
    """

    slowest: float = 2.0
    fastest: float = 10.0
    n_rates: int = 5
    n_output: int = 2
    w_range: tuple[float, float] = (0.05, 2.0)
    noise_range: tuple[float, float] = (1.0, 16.0)
    lock_box: float = 0.2
    name: str = "scheduled"

    def __post_init__(self):
        lo, hi = self.w_range
        if not (0 < lo < hi) or not (0 < self.slowest) or self.slowest * hi > self.fastest:
            raise ObserverError(f"w_range={self.w_range!r}, slowest={self.slowest!r}, "
                                f"fastest={self.fastest!r}: need 0 < low < high and "
                                "0 < slowest x high <= fastest")
        if self.n_rates < 2 or self.n_output < 1:
            raise ObserverError(f"n_rates={self.n_rates!r}, n_output={self.n_output!r}: "
                                "need at least 2 rates and 1 output")
        if not (0 < self.noise_range[0] <= self.noise_range[1]):
            raise ObserverError(f"noise_range={self.noise_range!r}: need 0 < low <= high")
        if not (0 < self.lock_box <= 1):
            raise ObserverError(f"lock_box={self.lock_box!r}: need 0 < lock_box <= 1")

    @property
    def q(self) -> int:
        return self.n_output * self.n_rates

    def rates(self, w: float) -> np.ndarray:
        """One bank's rates at gain w [1/s], slowest first, shape (n_rates,)."""
        frac = _fractions(self.n_rates)
        lo = self.slowest * w
        return lo * (self.fastest / lo) ** frac

    def rate_vector(self, w: float) -> np.ndarray:
        """The rate of every z component at gain w [1/s], shape (q,)."""
        return np.tile(self.rates(w), self.n_output)

    def channel(self) -> np.ndarray:
        """Which output drives each z component, shape (q,)."""
        return np.repeat(np.arange(self.n_output), self.n_rates)

    def check_stable(self, Te: float) -> None:
        if Te * self.fastest >= 2:
            raise ObserverError(f"fastest={self.fastest!r} at Te={Te!r} gives eigenvalues "
                                "outside (-1, 1)")

    def to_dict(self) -> dict:
        return {"name": self.name, "slowest": self.slowest, "fastest": self.fastest,
                "n_rates": self.n_rates, "n_output": self.n_output,
                "w_range": list(self.w_range), "noise_range": list(self.noise_range),
                "lock_box": self.lock_box}

    @classmethod
    def from_dict(cls, d: dict) -> ScheduledDesign:
        return cls(float(d["slowest"]), float(d["fastest"]), int(d["n_rates"]),
                   int(d["n_output"]), tuple(d["w_range"]), tuple(d["noise_range"]),
                   float(d["lock_box"]),
                   d.get("name", "scheduled"))


@dataclass(frozen=True)
class GainSchedule:
    """When the filters run at which gain w [-].

    ``w(t) = max(floor(s), start(s) / (1 + t / settle))``, clipped to the maps' range,
    with t the time since the last (re)start [s] and s the measurement noise over the
    nominal (in the model's gain). The memory grows with the time the estimate has had
    to settle (a Kalman filter's 1/k gain), down to ``floor(s) = quiet / s**noise_power``:
    more noise, longer averaging. A noisy link also starts slower,
    ``start(s) = start / s**start_power``: fast filters pass the noise to the decoder.

    Attributes:
        start: gain at a (re)start on a nominal link [-].
        settle: time for the gain to halve from the start [s].
        quiet: the floor on a nominal link [-].
        noise_power: how the floor falls with the noise [-].
        start_power: how the start falls with the noise [-].
        recover_power: how ``recover`` falls with the noise [-].
        recover: the least gain while the estimate is outside the locked box
            (converging, a slew, a kick), the clock held to match [-].
        step_ratio: w changes only by at least this factor (each change costs two
            encoder evaluations) [-].
        lock_after: slowest time constants the estimate must stay inside the locked
            box before the locked decoder takes over [-].
        lock_ramp: how long the take-over takes [s].
        settle_off: averaging time of the estimate's distance from the operating point
            for the lock and recover tests [s].
        jump: a distance of this many locked boxes acts at once (a kick) [-].
        disagree: the locked decoder is dropped when its estimate is this far from the
            wide one's, in domain half-widths (either component) [-].
        driven: while the input's mean magnitude |u - u_bar| (over ``driven_time``)
            exceeds this, the plant is being driven (the motor working against a load,
            as in a sea's waves or a current) and the gain is held at least at
            ``driven_gain`` times ``recover``'s, the clock held to match [u's units]
            (None: never; the paper's schedule).
        driven_time: the averaging time of that mean [s].
        driven_gain: the least gain while driven, in ``recover``'s [-].
    """

    start: float = 2.0
    settle: float = 0.25
    quiet: float = 0.7
    noise_power: float = 0.25
    start_power: float = 0.5
    recover_power: float = 0.5
    recover: float = 1.0
    step_ratio: float = 1.05
    lock_after: float = 1.0
    lock_ramp: float = 0.5
    settle_off: float = 0.1
    jump: float = 3.0
    disagree: float = 0.1
    driven: float | None = None
    driven_time: float = 0.5
    driven_gain: float = 1.0

    def __post_init__(self):
        positive = (self.start, self.settle, self.quiet, self.recover, self.lock_ramp,
                    self.settle_off, self.jump, self.disagree)
        if min(positive) <= 0 or self.step_ratio < 1 or \
                min(self.noise_power, self.start_power, self.recover_power,
                    self.lock_after) < 0:
            raise ObserverError(f"{self!r}: start, settle, quiet, recover, lock_ramp, "
                                "settle_off, jump, disagree > 0, "
                                "noise_power, start_power, recover_power, lock_after >= 0 and "
                                "step_ratio >= 1 are needed")

    def _scale(self, noise: float) -> float:
        return max(noise, 1e-9) ** self.start_power

    def recover_gain(self, noise: float) -> float:
        return self.recover / max(noise, 1e-9) ** self.recover_power

    def time_of(self, w: float, noise: float) -> float:
        """Time since the (re)start [s] at which the 1/t branch reaches w."""
        return max(self.settle * (self.start / self._scale(noise) / w - 1.0), 0.0)

    def floor(self, noise: float) -> float:
        return self.quiet / max(noise, 1e-9) ** self.noise_power

    def gain(self, t: float, noise: float) -> float:
        return max(self.floor(noise), self.start / self._scale(noise) / (1.0 + t / self.settle))


@functools.lru_cache(maxsize=8)
def _fractions(n: int) -> np.ndarray:
    """0 to 1 in n even steps (read-only: shared by every call)."""
    frac = np.linspace(0.0, 1.0, n)
    frac.flags.writeable = False
    return frac
