"""Link supervision: the same layer over every estimator (KKL, EKF, UKF, PF).

Each control step the supervisor rescales the powers to the estimator's model gain
(:class:`~observer.supervision.gain_tracking.GainTracker`: distance and LED angle scale both
photodiodes alike), runs the estimator, and checks its estimate against the
measurements (:class:`~observer.supervision.monitor.ResidualMonitor`). While the link is trusted
it remembers the gimbal's encoder angle. Once it is lost (after the warm-up) it takes
the motor and runs an :class:`~ledsim.agent.acquisition.AcquisitionScan` around the last
trusted angle, until the scan sees the beam well enough to re-seed the estimator and
the gain; then the control law has the motor again.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from ledsim.agent.acquisition import AcquisitionScan
from ledsim.agent.held import SEED_RATE_STD, HeldEstimate
from ledsim.agent.laws import intensity_maximum
from ledsim.agent.link_gain import link_gain_tracker
from ledsim.agent.slew import FastAcquisition
from ledsim.agent.step import Decision
from ledsim.constants import LinkConstants
from ledsim.radiometry.optics import (
    pair_phi_variance,
)
from observer.estimator import Estimator
from observer.supervision.monitor import ResidualMonitor
from observer.supervision.occlusion import EncoderCarry

#: The scan of a fast acquisition: it only has to bring the beam into view, so it sweeps
#: at 2 rad/s and widens by most of the field of view each half sweep (the fix takes
#: over within a few samples of light). It first waits 2 s where the beam was: a
#: gimbal that did not turn while blind was occluded, and finds the beam where it was.
FAST_SCAN = {"speed": 2.0, "widen": 0.4, "dwell": 2.0}
#: Encoder angle [rad] within which a never-lit gimbal is at its centre and scans.
CENTRE_REACHED = 0.05


#: Encoder travel [rad] since the last trusted step, while every photodiode is gated
#: out, that an occlusion cannot explain: the receiver itself turned off the beam (a
#: kick), so the link is lost now, not when the dropout gate gives up (1 s later).
BLIND_TRAVEL = 0.2

#: A sample held this long [s] is an occlusion, for the encoder to carry the estimate.
DEAD_RECKON_AFTER = 0.05
class LinkSupervisor:
    """Gain normalisation, loss detection, acquisition scan and re-seeding for one run.

    Args:
        estimator: the estimator it supervises (its ``system`` is the model).
        constants: the link.
        inertia: gimbal inertia about the hinge [kg m^2].
        warmup: no scan before this time [s] (the estimator is still converging).
        reacquire: scan for the beam when lost (False: only flag the loss).
        gain_ratio: initial link gain over the model's [-].
        noise_ratio: measurement noise in the model's gain over the model's nominal noise
            at the initial gain [-]. The sensor's own noise is known (the Bayesian filters
            are told it too); in the model's gain it scales as 1 / gain, so a bank of
            observers follows the tracked gain.
        dead_reckon: while a sample is gated out (an occlusion), the encoder in the line
            of sight's frame carries the estimate, and the estimator restarts from it
            when the light returns (:class:`~observer.supervision.occlusion.EncoderCarry`; for runs
            whose encoder angle is in that frame: the IMU's).
        fast: acquire at the torque limit (:class:`~ledsim.agent.slew.FastAcquisition`)
            at the start and after every loss, scanning only while the beam is out of
            view; its torque limit [N m] (None: the scan alone, after ``warmup``).
    """

    def __init__(self, estimator: Estimator, constants: LinkConstants, inertia: float,
                 warmup: float = 0.0, reacquire: bool = True, gain_ratio: float = 1.0,
                 noise_ratio: float = 1.0, dead_reckon: bool = False,
                 fast: float | None = None):
        self.estimator = estimator
        model = estimator.system
        self.monitor = ResidualMonitor(model, noise_ratio=noise_ratio)
        self.sensor_noise = noise_ratio * gain_ratio  # in the model's nominal noise
        self.gain = link_gain_tracker(model, constants, gain_ratio)
        self.fast = None
        if fast is not None and reacquire:
            self.fast = FastAcquisition(constants, inertia, fast, intensity_maximum(constants))
        self.scan = AcquisitionScan(constants, **({} if self.fast is None else FAST_SCAN))
        self.warmup = warmup
        self.reacquire = reacquire
        # Encoder angles of the last trusted steps: a loss is flagged up to about 0.2 s
        # late, so the scan centres on the oldest, from before the trouble began.
        self.trusted_q: deque = deque(maxlen=max(1, int(round(0.3 / constants.Te))))
        self.carry = EncoderCarry(constants.Te, DEAD_RECKON_AFTER) if dead_reckon else None
        self._angle = constants.layout.angle
        self._started = False
        # The model's nominal noise [W, model's gain], and the variance of phi that one
        # unit of it on each power gives at the alignment target [rad^2].
        self._nominal_std = float(np.mean(model.measurement_noise_std))
        target = intensity_maximum(constants)
        self._phi_variance_per_noise = pair_phi_variance(
            target, model.h(np.array([target, 0.0])), self._nominal_std, constants)
        self.held = HeldEstimate(estimator, self.fast, self._angle, self.trusted_q.maxlen)
        self._tell_noise()

    @property
    def outside_domain(self) -> bool:
        """The estimator says its estimate or its input left its training box
        (:attr:`~observer.estimator.Estimator.outside_domain`)."""
        return self.estimator.outside_domain

    @property
    def gain_ratio(self) -> float:
        """The link's gain over the model's that the powers are divided by [-]."""
        return float(self.gain.ratio)

    def noise_ratio(self) -> float:
        """Measurement noise in the model's gain over the model's nominal noise [-]: the
        sensor's noise over the tracked gain, and what a fading channel adds to the
        pair's shape (:attr:`~observer.supervision.fading.FadingChannel.shape_variance`, as the
        noise on each power that would put that variance on phi at the alignment
        target). (Not the monitor's learned noise: fast motion, such as a vibrating
        hull, inflates that and would pick a slow member; the shape's is what the
        encoder does not explain.)"""
        sensor = self.sensor_noise / self.gain.ratio
        shape = self.gain.channel.shape_variance
        if not shape:
            return float(sensor)
        return float(math.hypot(sensor, math.sqrt(shape / self._phi_variance_per_noise)))

    def _tell_noise(self, y: np.ndarray | None = None):
        """Tell the estimator the noise the powers carry (``y``: the step's, in the
        model's gain; None: before the run or at a restart): the noise ratio, or to a
        filter that models its sensor's noise the fading's factor on it (1 without).
        Returns the estimate when that changed it, else None."""
        ratio = self.noise_ratio()
        if self.estimator.models_its_noise:
            ratio /= self.sensor_noise / self.gain.ratio
        return self.estimator.adapt_noise(ratio, y)

    def sensor_std(self) -> float:
        """The sensor's own noise [W] on each power (what the fading is learned over)."""
        return float(self.sensor_noise * self._nominal_std)

    def predict(self, u) -> None:
        """Move the estimator to the next step under input ``u`` [rad/s^2]."""
        self.estimator.predict(u)

    def step(self, t: float, y: np.ndarray, q: float, qdot: float) -> Decision:
        """Step ``t`` [s]: gated powers ``y`` [W], encoder angle ``q`` [rad] and rate
        ``qdot`` [rad/s]. The estimator has taken the measurement when this returns.

        While the link is lost, the decision also holds the estimate the run reports
        instead of the estimator's, which the data no longer back
        (:class:`~ledsim.agent.held.HeldEstimate`)."""
        d = self._decide(t, y, q, qdot)
        self.held.observe(d, q, qdot)
        return d

    def _decide(self, t: float, y: np.ndarray, q: float, qdot: float) -> Decision:
        """:meth:`step`'s decision, before the held estimate."""
        est, scan = self.estimator, self.scan
        self.gain.sample(y, q, self.sensor_std())
        y_model = self.gain.normalize(y)
        xhat = est.update(y_model)
        if self.carry is not None:
            xhat = self.carry.step(est, xhat, y, y_model, q, qdot)
        if self.fast is not None and not self._started:  # the run's start
            self._started = True
            self.fast.start(q)
        if self.fast is not None and self.fast.active:
            return self._acquire(y, q, qdot, xhat)
        lost = self.monitor.update(y_model, xhat)
        finite = np.isfinite(y)
        blind = not finite.any()
        turned = blind and bool(self.trusted_q) and \
            abs(q - self.trusted_q[-1]) > BLIND_TRAVEL
        lost = lost or turned
        scan.record(y, q)
        if not (lost or scan.active):
            if not blind:  # only angles the beam confirmed: a spun gimbal's are not
                self.trusted_q.append(q)
            if self.carry is not None and finite.all():
                self.carry.lit = (float(self._angle(xhat)), q)
            self.gain.update(y, self.monitor.noise_std * self.gain.ratio)
            # A bank picks the member trained for the noise the rescaled powers now
            # carry, a gain-scheduled KKL its floor by it.
            adapted = self._tell_noise(self.gain.normalize(y))
            if adapted is not None:
                xhat = adapted
            return Decision(xhat, False)
        if t < self.warmup:  # still converging from the initial guess: not a lost link
            return Decision(xhat, False, reason="converging")
        reason = "turned off the beam while blind" if turned else self.monitor.reason
        if not self.reacquire:
            return Decision(xhat, True, reason=reason)
        if self.fast is not None:
            self.fast.start(q)
            return self._acquire(y, q, qdot, xhat)
        # Lost: re-seed from the last samples if they show the beam (no need to move),
        # else scan until they do.
        noise = float(np.mean(self.monitor.noise_std)) * self.gain.ratio
        fit = scan.fit(noise)
        if fit is not None:
            scan.stop()
            self.gain.refit(fit.gain / self.gain.model_gain)
            # phi = phi_home - q while the hull holds still, so phidot = -qdot.
            self._restart(np.array([fit.phi, -qdot]))
            xhat = est.update(self.gain.normalize(y))
            self._handed_over(q)
            return Decision(xhat, True, reseeded=True, reason="re-seeded")
        if not scan.active:
            scan.start(self.trusted_q[0] if self.trusted_q else q, q)
        return Decision(xhat, True, True, scan.command(q, qdot, noise), reason="acquiring")

    def _seed_covariance(self) -> np.ndarray:
        """How sure a restart from the fix is: phi within three of the fix's standard
        errors (its spread and the pair's model error: at one, an EKF trusted a 1-deg
        bias for seconds); phidot is the encoder's own."""
        return np.diag([(3 * self.fast.fix.stderr)**2, SEED_RATE_STD**2])

    def _restart(self, x0: np.ndarray, covariance: np.ndarray | None = None) -> None:
        """Restart the estimator from ``x0`` (with ``covariance``), told the noise the
        powers carry now: while the link was lost it was not told, and a channel that
        began to fade meanwhile would meet a filter sure of every sample."""
        self.estimator.reset(x0, covariance)
        self._tell_noise()

    def _handed_over(self, q: float) -> None:
        """The estimate is the link's again, at encoder angle ``q`` [rad]."""
        self.monitor.reset()
        self.trusted_q.clear()
        self.trusted_q.append(q)
        self.held.clear()

    def _acquire(self, y, q: float, qdot: float, xhat) -> Decision:
        """A step of the fast acquisition: hold, slew or scan, and the re-seed on arrival."""
        est, scan, fast = self.estimator, self.scan, self.fast
        noise = float(np.mean(self.monitor.noise_std)) * self.gain.ratio
        scan.record(y, q)
        u, seed = fast.step(y, q, qdot, noise, float(self._angle(xhat)),
                            self.gain.channel.shape_variance)
        if fast.prime is not None and seed is None:  # at the target: converge from there
            self._restart(np.array(fast.prime), self._seed_covariance())
            xhat = est.update(self.gain.normalize(y))
        if seed is not None:
            scan.stop()
            if fast.kept:  # weak light: the estimator's own estimate, which the fix backs
                self._handed_over(q)
                return Decision(xhat, True, reseeded=True, reason="acquired")
            if fast.fix.gain is not None and fast.fix.gain > 0:
                self.gain.refit(fast.fix.gain / self.gain.model_gain)
            self._restart(np.array(seed), self._seed_covariance())
            xhat = est.update(self.gain.normalize(y))
            self._handed_over(q)
            return Decision(xhat, True, reseeded=True, reason="acquired")
        if u is None:  # the beam is out of view: scan for it
            fast.q_hold = q
            if not (self.trusted_q or scan.active) and abs(q) > CENTRE_REACHED:
                # Never seen: the gimbal's centre first, at the torque limit (where a
                # receiver mounted to face its transmitter most likely finds it).
                return Decision(xhat, True, True, fast.slew.command(q, qdot, 0.0),
                                reason="acquiring")
            if not scan.active:  # around the last trusted angle, else the gimbal's centre
                scan.start(self.trusted_q[0] if self.trusted_q else 0.0, q,
                           dwell=None if self.trusted_q else 0.0)
            u = scan.command(q, qdot, noise)
        else:
            scan.stop()
        return Decision(xhat, True, True, u, reason="acquiring")
