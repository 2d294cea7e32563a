"""Acquisition at the torque limit: find where the beam is from the first samples, slew
there in near-minimum time on the encoder, and hand over to tracking on arrival.

Two pieces, each with one job:

- :class:`BeamFix` says where the beam is. Within the field of view the pair of powers
  fixes phi whatever the gain (:func:`~ledsim.optics.pair_shape_inverse`), and the encoder
  carries each sample to the present: the encoder angle at which phi would be the
  alignment target is ``q_k + phi_k - phi_ref`` for a sample taken at encoder angle
  ``q_k`` (phi = phi_home - q while the hull holds still; with the IMU, q is in the line
  of sight's frame). Samples are weighted by the inverse of their phi variance, from the
  noise and the slope of the log-ratio there; the fix is their weighted mean, and its
  standard error says when the evidence is enough.
- :class:`TimeOptimalSlew` moves the encoder there: a proximate time-optimal servo
  (PTOS; Workman, Kosut and Franklin, ACC 1987). Its rate reference is the braking curve
  ``sqrt(2 alpha a |e|)`` of a fraction ``alpha`` of the acceleration the torque limit
  gives, under a stiff rate loop, and linear near the target, so it neither chatters nor
  overshoots. Bang-bang over 0.3 rad takes 2 sqrt(0.3 / a) = 0.071 s with the shipped
  gimbal (a = 0.05 N m / 2.09e-4 kg m^2 = 239 rad/s^2); the water's drag and alpha add
  a little.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

from ..config import LinkConstants
from ..optics import pair_shape_inverse, response_and_slope


class BeamFix:
    """Where the beam is, in the encoder's frame, from the pair of powers.

    Args:
        constants: the link (the receiver response, dphi, Te).
        phi_ref: the alignment target, phi at the intensity maximum [rad].
        detect_sigmas: a sample counts when both powers are this many noise standard
            deviations above zero [-].
        max_phi: samples whose inverted |phi| exceeds this are left out [rad] (far in the
            tail the log-ratio is dominated by the shoulder's model error).
        memory: samples older than this are forgotten [s]: they may no longer hold (a
            drifting transmitter, a hull turning without the IMU).
        agree_sigmas: a sample further than this many standard deviations from the
            others' fix starts the fix afresh (the beam moved, or the older samples were
            a partly shaded pair, whose shape lies about phi) [-].
    """

    def __init__(self, constants: LinkConstants, phi_ref: float, detect_sigmas: float = 4.0,
                 max_phi: float = 0.8, memory: float = 0.3, agree_sigmas: float = 4.0):
        self.c = constants
        self.phi_ref = phi_ref
        self.detect_sigmas = detect_sigmas
        self.max_phi = max_phi
        self.memory_steps = max(1, int(round(memory / constants.Te)))
        self.agree_sigmas = agree_sigmas
        # (step, weight [1/rad^2], target encoder angle [rad], gain [W]) of each sample.
        self._samples: deque = deque()
        self._step = 0

    def clear(self) -> None:
        self._samples.clear()

    @property
    def samples(self) -> int:
        return len(self._samples)

    def add(self, y, q: float, noise_std: float) -> bool:
        """Take the powers ``y`` [W] measured at encoder angle ``q`` [rad] with noise
        ``noise_std`` [W] (one call a control step, usable or not); True when the sample
        was usable."""
        self._step += 1
        while self._samples and self._step - self._samples[0][0] > self.memory_steps:
            self._samples.popleft()
        powers = [float(v) for v in y]
        bar = self.detect_sigmas * noise_std
        if not all(p > bar for p in powers):  # dark, gated out (NaN) or in the noise
            return False
        phi, gain, _ = pair_shape_inverse(powers, self.c)
        if not abs(phi) <= self.max_phi:
            return False
        var = self.phi_variance(phi, powers, noise_std)
        if not var > 0 or not math.isfinite(var):
            return False
        target = q + phi - self.phi_ref
        if self._samples and abs(target - self.target) > self.agree_sigmas * math.sqrt(
                var + self.stderr**2):
            self._samples.clear()
        self._samples.append((self._step, 1.0 / var, target, gain))
        return True

    def phi_variance(self, phi: float, powers, noise_std: float) -> float:
        """Variance of one sample's inverted phi [rad^2]: the log-ratio's noise
        sigma^2 (1/P1^2 + 1/P2^2) over its squared slope in phi there (``powers`` [W])."""
        g1, dg1 = response_and_slope(phi, self.c.receiver)
        g2, dg2 = response_and_slope(phi + self.c.dphi, self.c.receiver)
        slope = dg1 / g1 - dg2 / g2
        if slope == 0:
            return math.inf
        return noise_std * noise_std * sum(1.0 / (p * p) for p in powers) / (slope * slope)

    def _weighted_mean(self, column: int) -> float | None:
        """The inverse-variance weighted mean of a sample column (None: no sample)."""
        w = sum(s[1] for s in self._samples)
        return sum(s[1] * s[column] for s in self._samples) / w if w > 0 else None

    @property
    def target(self) -> float | None:
        """Encoder angle [rad] at which phi is the alignment target (None: no sample)."""
        return self._weighted_mean(2)

    @property
    def stderr(self) -> float:
        """Standard error of :attr:`target` [rad] (inf: no sample)."""
        w = sum(s[1] for s in self._samples)
        return 1.0 / math.sqrt(w) if w > 0 else math.inf

    @property
    def gain(self) -> float | None:
        """The transmitter gain the samples saw [W], weighted as the target (None: no
        sample)."""
        return self._weighted_mean(3)


class TimeOptimalSlew:
    """A near-minimum-time move of the encoder angle, for a discrete controller.

    At 100 Hz a minimum-time slew of 0.3 rad is seven steps, too few for a continuous-time
    servo's loops to settle, so each step plans the next one: the rate to have one step
    from now is the braking curve ``sqrt(2 alpha a |e|)`` at the error expected then
    (``a`` the acceleration the torque limit gives, ``alpha`` a margin for the water's
    drag), capped near the target by ``settle / Te`` times that error (a deadbeat
    approach over 1 / settle steps), and the torque is what reaches that rate in one step
    (within the limit). This is the proximate time-optimal servo of Workman, Kosut and
    Franklin (ACC 1987) with its rate loop made deadbeat.

    Args:
        inertia: the gimbal's inertia about its hinge [kg m^2].
        limit: the motor's torque limit [N m].
        Te: the control period [s].
        alpha: share of the limit's acceleration the braking curve plans with [-].
        settle: share of the remaining error closed per step near the target [-].
    """

    def __init__(self, inertia: float, limit: float, Te: float, alpha: float = 0.9,
                 settle: float = 0.7):
        self.inertia = inertia
        self.limit = limit
        self.Te = Te
        self.accel = alpha * limit / inertia  # [rad/s^2]
        self.settle = settle

    def rate_reference(self, error: float) -> float:
        """The rate [rad/s] to move at with ``error`` [rad] left to go."""
        e = abs(error)
        return math.copysign(min(math.sqrt(2.0 * self.accel * e), self.settle * e / self.Te),
                             error)

    def torque(self, q: float, qdot: float, target: float,
               max_rate: float = math.inf) -> float:
        """Motor torque [N m] towards encoder angle ``target`` [rad] from angle ``q``
        [rad] and rate ``qdot`` [rad/s], no faster than ``max_rate`` [rad/s], within the
        limit."""
        ahead = target - q - qdot * self.Te  # the error one step from now, coasting
        want = self.rate_reference(ahead)
        want = min(max(want, -max_rate), max_rate)
        tau = self.inertia * (want - qdot) / self.Te
        return min(max(tau, -self.limit), self.limit)


@dataclass
class AcquisitionLog:
    """When one acquisition's stages ended, in control steps from its start (1: the
    first step; None: not reached): the first usable sample (the pair's inversion),
    the fix good enough to go, the slew at the fix's target, and the arrival (the
    hand-over to the estimator, once the fix is good enough for it)."""

    steps: int = 0
    first_seen: int | None = None
    go: int | None = None
    reached: int | None = None
    arrived: int | None = None


class FastAcquisition:
    """Sense, slew, hand over: the acquisition of a run's start and of a lost link.

    Each step it takes the powers into its :class:`BeamFix`. While the fix's standard
    error is above ``go_stderr`` the gimbal holds still (or, after ``dark_time`` without
    a usable sample, the beam is out of view and the caller scans); then it slews to the
    fix on :class:`TimeOptimalSlew`, refining the target with every sample on the way,
    and hands over once the encoder is within ``arrive_tol`` of it at under
    ``arrive_rate``, with a standard error under ``arrive_stderr`` (or under
    ``settle_stderr`` after one memory of the fix at the target, where the light is too
    weak for better): the estimator
    restarts from phi = phi_ref + (target - q), phidot = -qdot.

    Args:
        constants: the link; inertia [kg m^2] and limit [N m]: the gimbal's.
        phi_ref: the alignment target [rad].
        go_stderr, arrive_stderr: evidence needed to move, and to hand over [rad].
        arrive_tol [rad], arrive_rate [rad/s]: what counts as arrived.
        dark_time: time without a usable sample after which the beam is out of view [s].
        creep_rate: the speed towards a fix not yet good enough to slew to [rad/s].
        min_samples: samples the fix needs before the gimbal moves on it [-].
        settle_stderr: the fix's standard error under which it hands over after one
            memory at the target even above ``arrive_stderr`` (weak light) [rad].
    """

    def __init__(self, constants: LinkConstants, inertia: float, limit: float,
                 phi_ref: float, go_stderr: float = 0.1, arrive_stderr: float = 0.006,
                 arrive_tol: float = 0.005, arrive_rate: float = 0.3,
                 dark_time: float = 0.05, creep_rate: float = 1.0, min_samples: int = 1,
                 settle_stderr: float = 0.018):
        self.fix = BeamFix(constants, phi_ref)
        self.slew = TimeOptimalSlew(inertia, limit, constants.Te)
        self.phi_ref = phi_ref
        self.go_stderr, self.arrive_stderr = go_stderr, arrive_stderr
        self.arrive_tol, self.arrive_rate = arrive_tol, arrive_rate
        self.dark_steps = max(1, int(round(dark_time / constants.Te)))
        self.creep_rate = creep_rate
        self.min_samples = min_samples
        self.settle_stderr = settle_stderr
        self.active = False
        #: One :class:`AcquisitionLog` per acquisition, in order.
        self.log: list[AcquisitionLog] = []

    def start(self, q: float) -> None:
        """Begin acquiring, the gimbal at encoder angle ``q`` [rad]."""
        self.active = True
        self.fix.clear()
        self.q_hold = q
        self.dark = 0
        self.moving = False
        self.log.append(AcquisitionLog())

    @property
    def out_of_view(self) -> bool:
        """No usable sample for ``dark_time``: the beam is not in the field of view."""
        return self.dark >= self.dark_steps and not self.moving

    def step(self, y, q: float, qdot: float, noise_std: float):
        """(torque [N m] or None, seed) for the powers ``y`` [W] at encoder angle ``q``
        [rad] and rate ``qdot`` [rad/s] with noise ``noise_std`` [W]. torque None: the
        beam is out of view (the caller scans); seed: (phi [rad], phidot [rad/s]) to
        restart the estimator from on arrival (None: not yet)."""
        seen = self.fix.add(y, q, noise_std)
        self.dark = 0 if seen else self.dark + 1
        log = self.log[-1]
        log.steps += 1
        if seen and log.first_seen is None:
            log.first_seen = log.steps
        target, err = self.fix.target, self.fix.stderr
        if target is None:  # every sample forgotten: start over
            self.moving = False
        if target is None or (not self.moving and self.fix.samples < self.min_samples):
            if self.out_of_view:
                return None, None
            return self.slew.torque(q, qdot, self.q_hold), None
        if not self.moving and err > self.go_stderr:
            # Some evidence, not enough to go: creep towards it, where the light is
            # brighter and each sample tells more.
            return self.slew.torque(q, qdot, target, self.creep_rate), None
        if not self.moving:
            log.go = log.steps
        self.moving = True
        there = abs(target - q) < self.arrive_tol and abs(qdot) < self.arrive_rate
        if there and log.reached is None:
            log.reached = log.steps
        # The fix holds one memory's worth of samples: where the light is too weak for
        # them to reach arrive_stderr, waiting longer at the target gains nothing; a fix
        # worse than settle_stderr even so is not one to hand over on.
        settled = log.reached is not None and err < self.settle_stderr and \
            log.steps - log.reached >= self.fix.memory_steps
        if there and (err < self.arrive_stderr or settled):
            self.active = False
            log.arrived = log.steps
            return None, (self.phi_ref + (target - q), -qdot)
        return self.slew.torque(q, qdot, target), None
