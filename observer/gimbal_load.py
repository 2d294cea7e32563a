"""The load on a gimbal that its model does not explain (the water's torque on its
housing in a current), estimated in the model's own terms."""

from __future__ import annotations

import numpy as np


class LoadObserver:
    """The input the gimbal gets that its model does not explain (the water's torque on
    its housing in a current), from the encoder and the hull's gyro: a disturbance
    observer in the model's own terms, so the drag the model already has is not
    counted twice.

    With the line of sight still, phidot = -w, w = qdot + r the gimbal's inertial rate
    (encoder rate plus the hull's yaw rate; the hull's own turning does not move the
    gimbal, which is free on its hinge). The model predicts the next phidot from the
    input u the motor gave; what it misses, over the model's input gain, is the load d
    [rad/s^2] (low-passed over ``time``). The motor cancels it, so a current on the
    gimbal no longer waits for the slow integral of the rate loop.

    Args:
        model: the one-step model (``f(x, u)``, the identified MuJoCo model).
        time: the low-pass time constant [s].
        limit: the largest load it believes [rad/s^2] (60: 0.0125 N m on the shipped
            gimbal, beyond the water's torque at 0.5 m/s); an impulse (a kick) is not a
            load, and the loop must see it as a loss.
    """

    def __init__(self, model, time: float = 0.05, limit: float = 60.0):
        self.model = model
        self.limit = limit
        self.gain = min(1.0, model.Te / time)
        x = np.zeros(2)
        self.input_gain = float(model.f(x, 1.0)[1] - model.f(x, 0.0)[1])
        self.d = 0.0  # [rad/s^2], in u's terms
        self._rate: float | None = None

    def update(self, inertial_rate: float, u: float) -> float:
        """The load after this step, from the gimbal's inertial rate [rad/s] and the
        input u the motor gave over the last step [rad/s^2]."""
        if self._rate is not None:
            predicted = float(self.model.f(np.array([0.0, -self._rate]), u)[1])
            missed = (-inertial_rate - predicted) / self.input_gain
            missed = min(max(missed, -self.limit), self.limit)
            self.d += self.gain * (missed - self.d)
        self._rate = inertial_rate
        return self.d
