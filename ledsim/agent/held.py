"""The estimate a run reports while its link is lost.

Once the supervisor no longer trusts the estimator, the estimator's own estimate is
what the data no longer back (a KKL's decoder maps any z to some point of its box). The
run reports instead what the supervisor holds: the acquisition's fix of the beam once it
is sure enough, else the last trusted estimate carried on the gimbal's encoder, with its
standard deviation where the estimator has a covariance.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ledsim.agent.step import Decision

#: Standard deviation of a fast acquisition's re-seeded phidot [rad/s]: the encoder's
#: rate, off by the hull's own turning that the line of sight does not remove.
SEED_RATE_STD = 0.05
#: While the link is lost, an acquisition's fix of the beam with at most this standard
#: error [rad] is the estimate the run reports (else the last trusted one, carried).
HELD_FIX_STDERR = 0.01


class HeldEstimate:
    """What a supervisor holds while its link is lost, for one run.

    Args:
        estimator: the supervised estimator (its covariance, if it has one).
        fast: the minimum-time acquisition (:class:`~ledsim.agent.slew.FastAcquisition`;
            None: none).
        angle: the state's angle [rad] of an estimate (the layout's).
        memory: trusted steps remembered: a loss is flagged up to 0.2 s late, and an
            estimate running away meanwhile was still trusted, so the oldest is held.
    """

    def __init__(self, estimator, fast, angle, memory: int):
        self.estimator, self.fast, self.angle = estimator, fast, angle
        self._anchors: deque = deque(maxlen=memory)  # (phi [rad], q [rad]) trusted
        self._std: np.ndarray | None = None  # the held one's, taken when a loss begins

    def clear(self) -> None:
        """Forget the trusted estimates (a hand-over starts the estimate afresh)."""
        self._anchors.clear()

    def observe(self, d: Decision, q: float, qdot: float) -> None:
        """Take the decision ``d`` of a step at encoder angle ``q`` [rad] and rate
        ``qdot`` [rad/s] in the line of sight's frame: remember a trusted estimate, or
        give a lost one (not a re-seed's) the held estimate, ``d.held`` and
        ``d.held_std``: the fix (phi = phi_ref + (target - q)), else phi = phi_0 - (q -
        q_0) from the oldest trusted one; phidot = -qdot."""
        if not d.lost:
            self._anchors.append((float(self.angle(d.xhat)), q))
            self._std = None
            return
        if d.reseeded:
            return
        fast = self.fast
        if fast is not None and fast.active and fast.fix.stderr <= HELD_FIX_STDERR:
            # A fresh fix of the beam, carried on the encoder like the seed it becomes.
            d.held = np.array([fast.phi_ref + (fast.fix.target - q), -qdot])
            d.held_std = np.array([fast.fix.stderr, SEED_RATE_STD])
        elif self._anchors:
            phi0, q0 = self._anchors[0]
            if self._std is None:  # the loss begins: how sure the last estimate was
                cov = self.estimator.covariance()
                self._std = (np.full(2, np.nan) if cov is None
                             else np.sqrt(np.clip(np.diag(cov), 0.0, None)))
            d.held = np.array([phi0 - (q - q0), -qdot])
            d.held_std = None if np.isnan(self._std).all() else self._std
