"""Acquisition at the torque limit: find where the beam is from the first samples, slew
there in near-minimum time on the encoder, and hand over to tracking on arrival.

Two pieces, each with one job:

- :class:`BeamFix` says where the beam is. Within the field of view the pair of powers
  fixes phi whatever the gain (:func:`~ledsim.radiometry.optics.pair_shape_inverse`), and
  the encoder carries each sample to the present: the encoder angle at which phi would be the
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
from dataclasses import dataclass

import numpy as np

from ledsim.agent.axes import clip
from ledsim.agent.beamfix import BeamFix
from ledsim.constants import LinkConstants

__all__ = ["AcquisitionLog", "BeamFix", "FastAcquisition", "TimeOptimalSlew"]


class TimeOptimalSlew:
    """A near-minimum-time move of the encoder angle, for a discrete controller.

    At 100 Hz a minimum-time slew of 0.3 rad is seven steps, too few for a continuous-time
    servo's loops to settle, so each step plans the next one: the rate to have one step
    from now is the braking curve ``sqrt(2 alpha a |e|)`` at the error expected then
    (``a`` the acceleration the torque limit gives, ``alpha`` a margin for the water's
    drag), capped near the target by ``settle / Te`` times that error (a deadbeat
    approach over 1 / settle steps), and the command is the acceleration that reaches
    that rate in one step (within the torque limit's). This is the proximate
    time-optimal servo of Workman, Kosut and Franklin (ACC 1987) with its rate loop
    made deadbeat.

    Each axis moves on its own curve (:mod:`ledsim.agent.axes`: floats for one axis,
    arrays over several, with an inertia per axis).

    Args:
        inertia: the gimbal's inertia about its hinge [kg m^2] (one per axis, or one).
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
        self.u_limit = limit / inertia  # the acceleration the torque limit gives [rad/s^2]
        self.accel = alpha * self.u_limit  # [rad/s^2]
        self.settle = settle

    def rate_reference(self, error: float) -> float:
        """The rate [rad/s] to move at with ``error`` [rad] left to go."""
        e = abs(error)
        if isinstance(e, np.ndarray):
            return np.copysign(np.minimum(np.sqrt(2.0 * self.accel * e),
                                          self.settle * e / self.Te), error)
        return math.copysign(min(math.sqrt(2.0 * self.accel * e), self.settle * e / self.Te),
                             error)

    def command(self, q: float, qdot: float, target: float,
                max_rate: float = math.inf, target_rate=None) -> float:
        """The input u = phi'' [rad/s^2] (phi = phi_home - q, so q'' = -u) towards
        encoder angle ``target`` [rad] from angle ``q`` [rad] and rate ``qdot`` [rad/s],
        no faster than ``max_rate`` [rad/s], within the torque limit; a target that
        moves at ``target_rate`` [rad/s] has its rate added (None: it stands)."""
        ahead = target - q - qdot * self.Te  # the error one step from now, coasting
        want = self.rate_reference(ahead)
        want = clip(want, -max_rate, max_rate)
        if target_rate is not None:
            want = want + target_rate
        u = (qdot - want) / self.Te
        return clip(u, -self.u_limit, self.u_limit)


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
    weak for better): the estimator restarts from phi = phi_ref + (target - q),
    phidot = -qdot. Where the light is weaker still, the estimator restarts from the fix
    on the first arrival (``prime``) and runs on its own with the gimbal at the target,
    as in the warm-up; after ``patience`` s the stack hands over to it as it is
    (``kept``) once the fix agrees with its estimate within three standard errors.

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
        patience: time at the target after which it hands over to an estimate the fix
            agrees with [s] (the warm-up's 1 s: at 0.2 m the fix never got under
            ``settle_stderr``, and the link stayed in 'acquiring' for the whole run,
            held by the fix alone; restarting the estimator from so weak a fix lost the
            link again within 0.1 s).
        aim_sigmas: the slew's aim moves to a new fix only when it is this many of the
            fix's standard errors away [-].
    """

    def __init__(self, constants: LinkConstants, inertia: float, limit: float,
                 phi_ref: float, go_stderr: float = 0.1, arrive_stderr: float = 0.006,
                 arrive_tol: float = 0.005, arrive_rate: float = 0.3,
                 dark_time: float = 0.05, creep_rate: float = 1.0, min_samples: int = 1,
                 settle_stderr: float = 0.018, patience: float = 1.0,
                 aim_sigmas: float = 2.0):
        self.fix = BeamFix(constants, phi_ref)
        self.slew = TimeOptimalSlew(inertia, limit, constants.Te)
        self.phi_ref = phi_ref
        self.go_stderr, self.arrive_stderr = go_stderr, arrive_stderr
        self.arrive_tol, self.arrive_rate = arrive_tol, arrive_rate
        self.dark_steps = max(1, int(round(dark_time / constants.Te)))
        self.creep_rate = creep_rate
        self.min_samples = min_samples
        self.settle_stderr = settle_stderr
        self.aim_sigmas = aim_sigmas
        self.aim = None  # the encoder angle the slew goes to [rad]
        self.kept = False  # the last hand-over kept the estimator's own estimate
        self.prime = None  # a seed to restart the estimator from while waiting
        self.patience_steps = max(1, int(round(patience / constants.Te)))
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
        self.aim = None
        self.log.append(AcquisitionLog())

    @property
    def out_of_view(self) -> bool:
        """No usable sample for ``dark_time``: the beam is not in the field of view."""
        return self.dark >= self.dark_steps and not self.moving

    def step(self, y, q: float, qdot: float, noise_std: float,
             estimate: float | None = None, extra_variance: float = 0.0):
        """(u [rad/s^2] or None, seed) for the powers ``y`` [W] at encoder angle ``q``
        [rad] and rate ``qdot`` [rad/s] with noise ``noise_std`` [W] (and
        ``extra_variance`` [rad^2] on each sample's phi: :meth:`BeamFix.add`). u None:
        the beam is out of view (the caller scans); seed: (phi [rad], phidot [rad/s]) to
        restart the estimator from on arrival (None: not yet)."""
        seen = self.fix.add(y, q, noise_std, extra_variance)
        self.dark = 0 if seen else self.dark + 1
        log = self.log[-1]
        log.steps += 1
        if seen and log.first_seen is None:
            log.first_seen = log.steps
        target, err = self.fix.target, self.fix.stderr
        self.prime = None
        if target is None:  # every sample forgotten: start over
            self.moving = False
        if target is None or (not self.moving and self.fix.samples < self.min_samples):
            if self.out_of_view:
                return None, None
            return self.slew.command(q, qdot, self.q_hold), None
        if not self.moving and err > self.go_stderr:
            # Some evidence, not enough to go: creep towards it, where the light is
            # brighter and each sample tells more.
            return self.slew.command(q, qdot, target, self.creep_rate), None
        if not self.moving:
            log.go = log.steps
        self.moving = True
        # On the way, aim at every refinement of the fix. At the target, not at its
        # noise: a weak link's fix wanders by its standard error every sample, and a
        # deadbeat slew chasing it shook the gimbal at +-1 rad/s (at 0.2 m), which no
        # estimator converges on; on a weak fix (over settle_stderr) the gimbal holds
        # still until the hand-over (an outlier of the fix at 0.2 m sent it 0.35 rad
        # off the beam). The hand-over takes the latest fix.
        if self.aim is None or log.reached is None or (
                err <= self.settle_stderr and abs(target - self.aim) > self.aim_sigmas * err):
            self.aim = target
        there = abs(self.aim - q) < self.arrive_tol and abs(qdot) < self.arrive_rate
        seed = (self.phi_ref + (target - q), -qdot)
        if there and log.reached is None:
            log.reached = log.steps
            self.prime = seed
        # The fix holds one memory's worth of samples: where the light is too weak for
        # them to reach arrive_stderr, waiting longer at the target gains nothing; a fix
        # worse than settle_stderr even so is not one to hand over on, until the
        # estimator has had the warm-up's time to converge on its own.
        waited = -1 if log.reached is None else log.steps - log.reached
        settled = err < self.settle_stderr and waited >= self.fix.memory_steps
        # After patience, the estimator's own estimate, if the fix agrees with it.
        self.kept = not settled and waited >= self.patience_steps and \
            estimate is not None and abs(estimate - seed[0]) <= 3 * err
        if there and (err < self.arrive_stderr or settled or self.kept):
            self.active = False
            log.arrived = log.steps
            return None, seed
        return self.slew.command(q, qdot, self.aim), None
