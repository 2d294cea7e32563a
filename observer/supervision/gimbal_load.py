"""The load on a gimbal that its model does not explain (the water's torque on its
housing in a current or a wave), estimated in the model's own terms."""

from __future__ import annotations

import numpy as np


class LoadObserver:
    """The input the gimbal gets that its model does not explain (the water's torque on
    its housing), from the encoder and the hull's gyro: a disturbance observer in the
    model's own terms, so the drag the model already has is not counted twice.

    With the line of sight still, phidot = -w, w = qdot + r the gimbal's inertial rate
    (encoder rate plus the hull's yaw rate; the hull's own turning does not move the
    gimbal, which is free on its hinge). The model predicts the next phidot from the
    input u the motor gave; what it misses, over the model's input gain, is the load d
    [rad/s^2] of the last step. The motor cancels it, and the estimators are told it as
    part of their input.

    The load is tracked with its rate (an alpha-beta filter: the steady state of a
    Kalman filter whose load has a random-walk rate), and the estimate handed on is the
    one predicted for the next step. A wave's orbital flow turns the torque on an open
    head over by tens of rad/s^2 within a second (1.5 m, 8 s waves 4 m deep: up to 50,
    changing at about 80 rad/s^3). A plain low-pass of 0.05 s lagged it by up to 4
    rad/s^2: the estimators were told an input that was not the one the gimbal got, and
    a KKL's phidot drifted 0.3 rad/s off until its estimate left its box, twice a wave.
    Following the trend leaves a lag of the load's second derivative only.

    Args:
        model: the one-step model (``f(x, u)``, the identified MuJoCo model).
        alpha: the filter's gain on the load [-] (its rate's is alpha^2 / (2 - alpha),
            critically damped). At 0.6 the waves above left the KKL's phi 9e-4 rad off
            (0.12 with the low-pass), while in still water the gyro's noise left phidot's
            error where it was; 0.8 and a raw per-step load (1) were closer in waves and
            twice as noisy still.
        limit: the largest load it believes at once [rad/s^2] (60: 0.0125 N m on the
            shipped gimbal, the water's torque at 0.5 m/s); a step that misses more is
            an impulse (a kick), not a load: the estimate skips it, so the motor does not
            fight the kick and the loop sees it as a loss, as before the trend was
            followed (clipped to the limit and followed at once, it slowed a 12 rad/s
            kick enough to delay its detection by a step).
        max_load: the largest load it believes once it has lasted [rad/s^2] (the
            control step passes the motor's own limit: a larger load it could not cancel
            anyway; default ``limit``). While the gimbal turns no faster than
            ``still_rate`` [rad/s], a load that grows past ``limit`` (within ``jump``
            of the load tracked) is followed on; the cap is ``limit`` again once the
            load is back under it. A load that jumps past ``limit`` at once is still an
            impulse: unless the motor cancels it, it spins the gimbal by more than
            ``still_rate`` within a step. The water's torque on an
            open head 3 m under 1.5 m, 6 s beam seas reaches 67 rad/s^2: capped at 60,
            the rest drove phidot 0.35 rad/s off twice a wave, and every estimator
            declared the link lost 13 times in 40 s (0 when followed).
        jump: the largest change of a load within a step [rad/s^2] (a wave's changes by
            about 1 a step; the smallest kick of docs/kicks.md, 8 rad/s, by 800).
        still_rate: the gimbal's inertial rate [rad/s] up to which a lasting miss is a
            load and not the model's own error (it was identified for |phidot| <= 0.5
            rad/s; an acquisition's slews at 6 rad/s miss by up to 100 rad/s^2).
    """

    def __init__(self, model, alpha: float = 0.6, limit: float = 60.0,
                 max_load: float | None = None, jump: float = 60.0,
                 still_rate: float = 0.5):
        if not 0.0 < alpha <= 1.0:
            raise ValueError(f"alpha={alpha!r} is not allowed: must be in (0, 1]")
        self.model = model
        self.limit = limit
        self.max_load = limit if max_load is None else max(float(max_load), limit)
        self.jump = jump
        self.still_rate = still_rate
        self.alpha = float(alpha)
        self.beta = self.alpha**2 / (2.0 - self.alpha)
        self.Te = float(model.Te)
        x = np.zeros(2)
        self.input_gain = float(model.f(x, 1.0)[1] - model.f(x, 0.0)[1])
        self.d = 0.0  # the next step's load [rad/s^2], in u's terms
        self._load, self._trend = 0.0, 0.0  # the load predicted for the last step, its rate
        self._rate: float | None = None
        self.large = False  # following a load beyond ``limit``

    def _rate_step(self, rate: float, u: float) -> float:
        """The model's next rate [rad/s] from ``rate`` under ``u``: f's second
        component, in plain floats where the model gives its coefficients
        (``rate_coefficients``: b1 r + b2 u + b3 |r| r, in f's order)."""
        coefs = getattr(self.model, "rate_coefficients", None)
        if coefs is None:
            return float(self.model.f(np.array([0.0, rate]), u)[1])
        b1, b2, b3 = coefs
        u, drag = float(u), abs(rate) * rate
        return b1 * rate + b2 * u + b3 * drag

    def update(self, inertial_rate: float, u: float) -> float:
        """The load predicted for the next step [rad/s^2], from the gimbal's inertial
        rate [rad/s] and the input u the motor gave over the last step [rad/s^2]."""
        if self._rate is not None:
            predicted = self._rate_step(-self._rate, u)
            missed = (-inertial_rate - predicted) / self.input_gain
            still = abs(inertial_rate) <= self.still_rate
            if self.large or abs(missed) > self.limit:
                # Past the limit, a load that grew there is followed on; a miss that
                # jumps, or one while the gimbal spins, is an impulse (a kick) or the
                # model's own error.
                if not still or abs(missed - self._load) > self.jump:
                    if self.large:  # back under the limit: a load no longer tracked
                        self.large, self._trend = False, 0.0  # cannot stay believed
                        self._load = self.d = min(max(self._load, -self.limit), self.limit)
                    self._rate = inertial_rate
                    return self.d
                self.large = abs(missed) > self.limit
            cap = self.max_load if self.large else self.limit
            residual = missed - self._load
            self._trend += self.beta / self.Te * residual
            # Past the cap the trend would only wind up (an impulse is no load).
            self._trend = min(max(self._trend, -cap / self.Te), cap / self.Te)
            self._load += self.alpha * residual + self.Te * self._trend
            self._load = min(max(self._load, -cap), cap)
            self.d = self._load
        self._rate = inertial_rate
        return self.d
