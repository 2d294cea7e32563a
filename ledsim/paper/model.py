"""The paper's closed-form LED link model, eqs. (eq-2a) and (eq-4a), as a DiscreteSystem.

    x = (phi [rad], phidot [rad/s])
    x1' = x1 + Te x2 + w1,    x2' = x2 + Te u + w2        (u: angular acceleration [rad/s^2])
    y   = Cp_bar [g(x1), g(x1 + dphi)] + v,    Cp_bar = a exp(-b d) I~(theta) / d^2

The paper writes ``x2' = x2 + u``; with its input functions (amplitude 0.1-0.2) read as a
per-step increment, x2 leaves the training box within a few steps, so u is read as an
angular acceleration and enters as ``Te u`` (``docs/model.md``).
"""

from __future__ import annotations

import numpy as np

from ledsim.constants import LinkConstants
from ledsim.radiometry.optics import (
    layout_power,
    layout_power_jacobian,
    plausible_power_range,
    step_form,
    transmitter_gain,
)
from observer.system import DiscreteSystem


class LEDLinkModel(DiscreteSystem):
    """Receiver gimbal angle and rate seen through two photodiodes ``dphi`` apart.

    =========  =====================================  =======
    symbol     meaning                                unit
    =========  =====================================  =======
    x[0]       incidence angle phi at photodiode 1    rad
    x[1]       angular rate phidot                    rad/s
    u          angular acceleration command           rad/s^2
    y[0]       photodiode_power of photodiode 1       W
    y[1]       photodiode_power of photodiode 2       W
    =========  =====================================  =======
    """

    n_state = 2
    n_output = 2
    n_input = 1
    state_names = ("phi [rad]", "phidot [rad/s]")
    output_names = ("P1 [W]", "P2 [W]")

    def __init__(self, constants: LinkConstants | None = None,
                 domain: tuple[float, float] = (0.5, 0.5)):
        self.constants = constants or LinkConstants()
        c = self.constants
        self.set_model(c.Te, domain, c.process_noise_std, c.measurement_noise(),
                       plausible_power_range(c))
        self.cp_bar = float(transmitter_gain(c.distance, c.theta, c))
        self._F = np.array([[1.0, c.Te], [0.0, 1.0]])

    def f(self, x, u=0.0):
        x = np.asarray(x, dtype=float)
        u = self.input_array(u, x.shape[:-1])[..., 0]
        return np.stack([x[..., 0] + self.Te * x[..., 1], x[..., 1] + self.Te * u], axis=-1)

    def step_form(self):
        """f and h for an exported observer (:class:`observer.kkl.export.StepForm`)."""
        return step_form((self.Te, 0.0, 0.0), (1.0, self.Te, 0.0), self.cp_bar,
                         self.constants, self.output_low, self.output_high)

    def f_inverse(self, x, u=0.0):
        """x_k from x_{k+1} (the model is time-reversible, paper Assumption 1)."""
        x = np.asarray(x, dtype=float)
        u = self.input_array(u, x.shape[:-1])[..., 0]
        x2 = x[..., 1] - self.Te * u
        return np.stack([x[..., 0] - self.Te * x2, x2], axis=-1)

    def h(self, x):
        return layout_power(self.cp_bar, self.constants.layout.angle(x), self.constants)

    def f_jacobian(self, x, u=0.0, eps=None):
        return np.broadcast_to(self._F, np.shape(x)[:-1] + (2, 2)).copy()

    def h_jacobian(self, x, eps=None):
        return layout_power_jacobian(self.cp_bar, self.constants.layout.angle(x),
                                     self.constants)

    def metadata(self) -> dict:
        meta = super().metadata()
        meta["constants"] = self.constants.to_dict()
        return meta
