"""The MuJoCo world seen through the observer's system interface.

State, input and output in the paper's terms, so the same training and estimators run
on the simulator:

=======  =================================================  =======
symbol   meaning                                            unit
=======  =================================================  =======
x[0]     incidence angle phi of photodiode 1                rad
x[1]     its rate phidot                                    rad/s
u        commanded angular acceleration of phi              rad/s^2
y        noise-free powers of the two photodiodes           W
=======  =================================================  =======

**Input mapping.** The motor torque is ``tau = -I u`` with ``I`` the gimbal's inertia
about the hinge (from MuJoCo's mass matrix): phi = phi0 - q, so a torque tau gives
phi'' = -tau / I before water drag and bearing damping, which the simulator adds on
its own. Training data (``f``), the Omega correction and every controller go through
:meth:`GimbalSystem.torque_for`, so the three agree. The torque limit clips |u| at
``torque_limit / I``.

``f`` is evaluated by setting MuJoCo's state (hull and LED at rest at home) and stepping
Te: the simulator, not a closed form, defines it. :class:`IdentifiedGimbalModel` is a
cheap one-step model fitted to the same transitions, for filters that need f thousands
of times per step (UKF sigma points, particle filter) and optionally for Omega.
"""

from __future__ import annotations

import numpy as np

from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld, WorldConfig
from ledsim.radiometry.optics import (
    layout_power,
    layout_power_jacobian,
    plausible_power_range,
    receiver_response_at,
    step_form,
)
from observer.system import DiscreteSystem


class GimbalSystem(DiscreteSystem):
    """:class:`DiscreteSystem` whose f and h are the MuJoCo world and its ray sensor."""

    n_state = 2
    n_output = 2
    n_input = 1
    state_names = ("phi [rad]", "phidot [rad/s]")
    output_names = ("P1 [W]", "P2 [W]")

    #: Calls with at least this many states go through :class:`GimbalBatch` (the same
    #: numbers, several times faster).
    BATCH_MIN = 32

    def __init__(self, config: WorldConfig | None = None,
                 domain: tuple[float, float] = (0.5, 0.5), threads: int = 1):
        if int(threads) < 1:
            raise ValueError(f"threads={threads!r}: need at least 1")
        self.threads = int(threads)
        self._batch = None  # GimbalBatch, built on the first large call
        self.config = config or WorldConfig()
        self.config.constants.layout.validate()  # x = (phi, phidot): one axis
        self.world = LinkWorld(self.config)
        self.sensor = IrradianceSensor(self.world, noise=False)
        c = self.config.constants
        self.constants = c
        self.set_model(c.Te, domain, c.process_noise_std, c.measurement_noise(),
                       plausible_power_range(c))
        self.inertia = self.world.hinge_inertia()
        self.world.reset()
        # phi at gimbal angle 0: the reference photodiode's incidence angle
        self.phi_home = float(self.sensor.geometry()[2][c.layout.reference])

    # -- the input mapping -----------------------------------------------------------

    def torque_for(self, u) -> np.ndarray:
        """Motor torque [N m] that commands angular acceleration ``u`` [rad/s^2] of phi."""
        return -self.inertia * np.asarray(u, dtype=float)

    # -- f and h by simulation -----------------------------------------------------------

    def _set_state(self, x) -> None:
        self.world.reset(gimbal_angle=self.phi_home - x[0], gimbal_rate=-x[1])

    def batched(self):
        """The :class:`~ledsim.physics.gimbal_system_batch.GimbalBatch` of this system."""
        if self._batch is None:
            from ledsim.physics.gimbal_system_batch import GimbalBatch

            self._batch = GimbalBatch(self.world, self.phi_home, self.threads)
        return self._batch

    def close(self) -> None:
        """Stop the batch's threads (if any were started)."""
        if self._batch is not None:
            self._batch.close()
            self._batch = None

    def f(self, x, u=0.0):
        x = np.asarray(x, dtype=float)
        batch = x.reshape(-1, 2)
        torques = self.torque_for(self.input_array(u, x.shape[:-1])[..., 0]).reshape(-1)
        if len(batch) >= self.BATCH_MIN:
            return self.batched().f(batch, torques).reshape(x.shape)
        out = np.empty_like(batch)
        w = self.world
        for k, (xk, tau) in enumerate(zip(batch, torques, strict=True)):
            self._set_state(xk)
            w.set_torque(tau)
            w.step()
            w.forward_kinematics()
            out[k] = self.phi_home - w.gimbal_angle, self.sensor.incidence_rate(0)
        return out.reshape(x.shape)

    def h(self, x):
        x = np.asarray(x, dtype=float)
        batch = x.reshape(-1, 2)
        if len(batch) >= self.BATCH_MIN:
            return self.batched().h(batch).reshape(x.shape[:-1] + (2,))
        geo = np.empty((len(batch), 4, 2))  # d, theta, phi, visible fraction per sample
        for k, xk in enumerate(batch):
            self._set_state(xk)
            geo[k] = self.sensor.geometry()
        power = self.sensor.clean_power(geo[:, 0], geo[:, 1], geo[:, 2], geo[:, 3])
        return power.reshape(x.shape[:-1] + (2,))

    def metadata(self) -> dict:
        meta = super().metadata()
        meta["constants"] = self.constants.to_dict()
        meta["world"] = world_metadata(self.config, self.inertia)
        return meta


def world_metadata(config: WorldConfig, inertia, **more) -> dict:
    """What a checkpoint is checked against of a world ``config`` whose hinges have
    ``inertia`` [kg m^2] (and ``more``)."""
    return {"timestep": config.timestep, "water_density": config.water_density,
            "water_viscosity": config.water_viscosity,
            "gimbal_damping": config.gimbal_damping, "hinge_inertia": inertia, **more}


class IdentifiedGimbalModel(DiscreteSystem):
    """One-step model fitted to MuJoCo transitions (cheap f, analytic Jacobians).

        phi'    = phi + a1 phidot + a2 u + a3 |phidot| phidot
        phidot' = b1 phidot + b2 u + b3 |phidot| phidot        (linear + quadratic drag)
        y       = k [g(phi), g(phi + dphi)]                    (k fitted, g the datasheet)
    """

    n_state = 2
    n_output = 2
    n_input = 1
    state_names = GimbalSystem.state_names
    output_names = GimbalSystem.output_names

    def __init__(self, source: GimbalSystem, coef_phi, coef_rate, power_gain: float):
        self.source_metadata = source.metadata()
        self.constants = source.constants
        self.Te = source.Te
        self.domain_low, self.domain_high = source.domain_low, source.domain_high
        self.process_noise_std = source.process_noise_std
        self.measurement_noise = source.measurement_noise
        self.measurement_noise_std = source.measurement_noise_std
        self.output_low, self.output_high = source.output_low, source.output_high
        self.coef_phi = np.asarray(coef_phi, dtype=float)
        self.coef_rate = np.asarray(coef_rate, dtype=float)
        self._coef_phi, self._coef_rate = self.coef_phi.tolist(), self.coef_rate.tolist()
        self.power_gain = float(power_gain)
        self._offsets = self.constants.layout.offsets
        self.inertia = source.inertia
        self.torque_for = source.torque_for

    @classmethod
    def fit(cls, source: GimbalSystem, n: int = 4000, seed: int = 0,
            u_max: float = 20.0) -> IdentifiedGimbalModel:
        """Least-squares fit on ``n`` random transitions of the simulator."""
        rng = np.random.default_rng(seed)
        x = source.sample_domain(rng, n)
        u = rng.uniform(-u_max, u_max, n)
        xn = source.f(x, u)
        feats = np.stack([x[:, 1], u, np.abs(x[:, 1]) * x[:, 1]], axis=1)
        coef_phi = np.linalg.lstsq(feats, xn[:, 0] - x[:, 0], rcond=None)[0]
        coef_rate = np.linalg.lstsq(feats, xn[:, 1], rcond=None)[0]
        phis = np.linspace(-0.6, 0.6, 61)
        y = source.h(np.stack([phis, 0 * phis], -1))
        g = layout_power(1.0, phis, source.constants)
        gain = float((g * y).sum() / (g * g).sum())
        return cls(source, coef_phi, coef_rate, gain)

    def _features(self, x, u):
        x = np.asarray(x, dtype=float)
        u = self.input_array(u, x.shape[:-1])[..., 0]
        return x, np.stack([x[..., 1], u, np.abs(x[..., 1]) * x[..., 1]], axis=-1)

    def f(self, x, u=0.0):
        if np.ndim(x) == 1 and np.ndim(u) == 0:  # one sample: plain floats, ~10x faster
            phi, rate = float(x[0]), float(x[1])
            u, drag = float(u), abs(rate) * rate
            (a1, a2, a3), (b1, b2, b3) = self._coef_phi, self._coef_rate
            return np.array([phi + (a1 * rate + a2 * u + a3 * drag),
                             b1 * rate + b2 * u + b3 * drag])
        x, feats = self._features(x, u)
        return np.stack([x[..., 0] + feats @ self.coef_phi, feats @ self.coef_rate], axis=-1)

    def h(self, x):
        if np.ndim(x) == 1:  # one sample: plain floats
            phi, r, k = float(x[0]), self.constants.receiver, self.power_gain
            return np.array([k * receiver_response_at(phi + o, r) for o in self._offsets])
        return layout_power(self.power_gain, self.constants.layout.angle(x), self.constants)

    def compiled_h(self) -> tuple:
        """h as the compiled kernels take it (:mod:`observer.supervision.compiled_monitor`):
        (the power gain [W], the photodiodes' offsets [rad], the response's a1, b1, c1,
        a2, b2, c2)."""
        r = self.constants.receiver
        return (self.power_gain, np.asarray(self._offsets, dtype=float),
                np.array([r.a1, r.b1, r.c1, r.a2, r.b2, r.c2], dtype=float))

    @property
    def rate_coefficients(self) -> tuple[float, float, float]:
        """(b1, b2, b3) of the rate's step, rate' = b1 rate + b2 u + b3 |rate| rate."""
        return tuple(self._coef_rate)

    def compiled_f(self) -> tuple:
        """f as the compiled kernels take it (:mod:`observer.baselines.compiled_ekf`): the
        coefficients (a1, a2, a3) and (b1, b2, b3) of the class docstring."""
        return self.coef_phi.copy(), self.coef_rate.copy()

    def step_form(self):
        """f and h for an exported observer (:class:`observer.kkl.export.StepForm`)."""
        return step_form(self.coef_phi, self.coef_rate, self.power_gain, self.constants,
                         self.output_low, self.output_high)

    def f_jacobian(self, x, u=0.0, eps=None):
        x = np.asarray(x, dtype=float)
        d_drag = 2 * np.abs(x[..., 1])
        jac = np.zeros(x.shape[:-1] + (2, 2))
        jac[..., 0, 0] = 1.0
        jac[..., 0, 1] = self.coef_phi[0] + self.coef_phi[2] * d_drag
        jac[..., 1, 1] = self.coef_rate[0] + self.coef_rate[2] * d_drag
        return jac

    def h_jacobian(self, x, eps=None):
        return layout_power_jacobian(self.power_gain, self.constants.layout.angle(x),
                                     self.constants)

    def metadata(self) -> dict:
        meta = dict(self.source_metadata)
        meta["class"] = type(self).__name__
        return meta
