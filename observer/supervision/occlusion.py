"""Through an occlusion, the estimate carried on the gimbal's encoder.

While a photodiode's sample is withheld (an occluder cuts the beam), the powers say
nothing about phi, but the encoder, in the line of sight's frame, still measures how far
the receiver turned: phi = phi_0 - (q - q_0) from the last fully lit step (phi_0 the
estimate then, q_0 the encoder). When every sample is back after a hold of at least
``restart_after`` (a dim link's short holds are not occlusions), the estimator restarts
from the carried state, as sure of it as it was when the gate closed.
"""

from __future__ import annotations

import numpy as np


class EncoderCarry:
    """The carry of the module docstring, for one run.

    Args:
        Te: step [s].
        restart_after: the shortest hold after which the estimator restarts [s].
    """

    def __init__(self, Te: float, restart_after: float):
        self.Te, self.restart_after = Te, restart_after
        self.lit: tuple[float, float] | None = None  # (phi, q) of the last lit step
        self._anchor: tuple[float, float] | None = None  # ... when the gate closed
        self._anchor_cov: np.ndarray | None = None  # the estimator's covariance then
        self._gated = 0

    def step(self, estimator, xhat, y, y_model, q: float, qdot: float) -> np.ndarray:
        """The estimate of this step: ``xhat`` (the estimator's, from ``y_model``, the
        powers in its model's gain) unless samples of ``y`` [W] are withheld, then the
        encoder's (``q`` [rad], ``qdot`` [rad/s])."""
        gated = not np.isfinite(y).all()
        if gated:
            self._gated += 1
            if self._gated == 1:
                self._anchor = self.lit
                cov = estimator.covariance()
                self._anchor_cov = None if cov is None else np.array(cov, dtype=float)
        held, self._gated = self._gated, self._gated if gated else 0
        if self._anchor is None:
            return xhat
        phi0, q0 = self._anchor
        carried = np.array([phi0 - (q - q0), -qdot])
        if gated:
            return carried
        self._anchor = None
        if held * self.Te < self.restart_after:
            return xhat
        # As sure as it was when the gate closed: the encoder carried the estimate
        # without adding to its error (a filter restarted from its initial spread, the
        # whole box, re-converged for seconds, at times off the beam).
        estimator.reset(carried, self._anchor_cov)
        return estimator.update(y_model)
