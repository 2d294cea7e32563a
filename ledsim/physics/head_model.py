"""A pan-tilt head seen through the observer's system interface: the two-axis model the
estimators use, one dimension up from the paper's.

=======  ==========================================================  =======
symbol   meaning                                                     unit
=======  ==========================================================  =======
x[0:2]   the line of sight's azimuth and elevation from the boresight  rad
x[2:4]   their rates                                                 rad/s
u        commanded angular acceleration of each angle                rad/s^2
y        each photodiode's noise-free power                          W
=======  ==========================================================  =======

Both axes turn as the pan does (:data:`~ledsim.physics.layout.ELEVATION`): an angle is
its home value less the encoder's, and a motor torque tau gives angle'' = -tau / I.

``f`` is fitted per axis to MuJoCo transitions of the head (as
:class:`~ledsim.physics.gimbal_system.IdentifiedGimbalModel` is for one axis), with
linear and quadratic drag, and each axis driven by its own input:

    angle' = angle + a1 rate + a2 u + a3 |rate| rate
    rate'  = b1 rate + b2 u + b3 |rate| rate

``h`` is :func:`~ledsim.radiometry.optics.head_power` times a gain fitted to the ray
sensor: the ray sensor matches it to 3e-4 within 0.1 rad of the boresight and 7e-3
within 0.3 rad (``tests/test_quad_optics.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ledsim.physics.world import LinkWorld
from ledsim.radiometry.optics import (
    head_power,
    plausible_power_range,
    receiver_response,
    response_slope,
    response_terms,
)
from ledsim.radiometry.optics import receiver_response_derivative as slope
from observer.system import DiscreteSystem


class HeadModel(DiscreteSystem):
    """The :mod:`two-axis model <ledsim.physics.head_model>` of a pan-tilt head.

    Its ``h`` is good to :attr:`model_error` of each power over the field of view the
    head works in; the Gaussian filters count that share with the noise (at luma's
    30 m the noise is 5e-5 of the power, and an EKF that trusted h to that diverged).

    Args:
        constants: the link, with its two-axis layout (``receiver_layout``).
        coef_angle, coef_rate: (a1, a2, a3) and (b1, b2, b3) per axis, shape (2, 3).
        power_gain: the gain that multiplies :func:`head_power` [W].
        inertia: each hinge's inertia [kg m^2], shape (2,) (a torque is -I u).
        domain: half-widths of the angles [rad] and the rates [rad/s] of the box.
        noise_scale: multiplies the measurement noise [-].
        channel_gains: each photodiode's responsivity over its nominal, as the head was
            calibrated [-] (None: all 1); h is what the channels put out.
    """

    n_state = 4
    n_input = 2
    #: The relative error of ``h`` [-]: the ray sensor's worst within 0.3 rad of the
    #: boresight is 7e-3 (the cone taken as separable, the pan-tilt's coupling), within
    #: 0.1 rad 3e-4 (the photodiodes' parallax).
    model_error = 3e-3

    def __init__(self, constants, coef_angle, coef_rate, power_gain: float, inertia,
                 domain: tuple[float, float] = (0.5, 0.5), noise_scale: float = 1.0,
                 channel_gains=None):
        layout = constants.layout
        if layout.n_axes != 2:
            raise ValueError(f"a head model needs a layout of two axes, not "
                             f"{layout.n_axes}")
        self.constants = constants
        self.n_output = layout.n_photodiodes
        self.state_names = ("azimuth [rad]", "elevation [rad]", "azimuth rate [rad/s]",
                            "elevation rate [rad/s]")
        self.output_names = tuple(f"{p.series} [W]" for p in layout.photodiodes)
        angle_noise, rate_noise = np.asarray(constants.process_noise_std, dtype=float)
        self.set_model(constants.Te, [domain[0]] * 2 + [domain[1]] * 2,
                       [angle_noise] * 2 + [rate_noise] * 2,
                       constants.measurement_noise(noise_scale),
                       plausible_power_range(constants))
        self.coef_angle = np.asarray(coef_angle, dtype=float).reshape(2, 3)
        self.coef_rate = np.asarray(coef_rate, dtype=float).reshape(2, 3)
        self.power_gain = float(power_gain)
        self.inertia = np.asarray(inertia, dtype=float).reshape(2)
        self._offsets = np.array([p.offset for p in layout.photodiodes])
        self._tilts = np.array([p.tilt for p in layout.photodiodes])
        # the plain-float paths' constants
        self._coefs = list(zip(self.coef_angle.tolist(), self.coef_rate.tolist(),
                               strict=True))
        self._directions = [(p.offset, p.tilt) for p in layout.photodiodes]
        self._cone = constants.link is not None
        self.channel_gains = np.ones(self.n_output) if channel_gains is None else \
            np.asarray(channel_gains, dtype=float).reshape(self.n_output)
        self._gains = self.channel_gains.tolist()
        self._last = None  # (angles, h, its Jacobian) of the last one-sample call

    def calibrated(self, channel_gains) -> HeadModel:
        """This model told the head's calibration: its channels' ``channel_gains`` [-]."""
        return HeadModel(self.constants, self.coef_angle, self.coef_rate, self.power_gain,
                         self.inertia, (self.domain_high[0], self.domain_high[2]),
                         self.measurement_noise.scale, channel_gains)

    def set_power_gain(self, gain: float) -> None:
        """Compute with the power gain ``gain`` [W] from now on (a moving vehicle's
        range: :class:`~ledsim.agent.range_gain.RangeGain`)."""
        self.power_gain, self._last = float(gain), None

    # -- the input mapping -----------------------------------------------------------

    def torque_for(self, u) -> np.ndarray:
        """Each motor's torque [N m] that commands angular acceleration ``u`` [rad/s^2]
        of its angle."""
        return -self.inertia * np.asarray(u, dtype=float)

    # -- f, h and their Jacobians ----------------------------------------------------

    def _features(self, x, u):
        """(rate, u, |rate| rate) per axis, shape (..., 2, 3)."""
        x = np.asarray(x, dtype=float)
        u = self.input_array(u, x.shape[:-1])
        rate = x[..., 2:]
        return x, np.stack([rate, u, np.abs(rate) * rate], axis=-1)

    def f(self, x, u=0.0):
        if np.ndim(x) == 1 and np.ndim(u) == 1:  # one sample: plain floats, ~10x faster
            out = [0.0] * 4
            xs, us = x.tolist(), u.tolist()
            for a, ((a1, a2, a3), (b1, b2, b3)) in enumerate(self._coefs):
                rate, v = xs[2 + a], us[a]
                drag = abs(rate) * rate
                out[a] = xs[a] + (a1 * rate + a2 * v + a3 * drag)
                out[2 + a] = b1 * rate + b2 * v + b3 * drag
            return np.array(out)
        x, feats = self._features(x, u)
        angles = x[..., :2] + np.einsum("...ak,ak->...a", feats, self.coef_angle)
        rates = np.einsum("...ak,ak->...a", feats, self.coef_rate)
        return np.concatenate([angles, rates], axis=-1)

    def f_jacobian(self, x, u=0.0, eps=None):
        if np.ndim(x) == 1:  # one sample: plain floats
            jac = np.eye(4)
            for a, ((a1, _, a3), (b1, _, b3)) in enumerate(self._coefs):
                d_drag = 2 * abs(float(x[2 + a]))
                jac[a, 2 + a] = a1 + a3 * d_drag
                jac[2 + a, 2 + a] = b1 + b3 * d_drag
            return jac
        x = np.asarray(x, dtype=float)
        d_drag = 2 * np.abs(x[..., 2:])  # d(|r| r)/dr, per axis
        jac = np.zeros(x.shape[:-1] + (4, 4))
        for a in range(2):
            jac[..., a, a] = 1.0
            jac[..., a, 2 + a] = self.coef_angle[a, 0] + self.coef_angle[a, 2] * d_drag[..., a]
            jac[..., 2 + a, 2 + a] = self.coef_rate[a, 0] + \
                self.coef_rate[a, 2] * d_drag[..., a]
        return jac

    def h(self, x):
        if np.ndim(x) == 1:  # one sample: plain floats
            g, _ = self._responses(x)
            return np.array(g)
        az, el = self.constants.layout.angles(np.asarray(x, dtype=float))
        return head_power(self.power_gain, az, el, self.constants) * self.channel_gains

    def h_jacobian(self, x, eps=None):
        """d(h)/dx, shape (..., n_photodiodes, 4): each power's slope in azimuth and in
        elevation (the rates do not reach the powers)."""
        if np.ndim(x) == 1:  # one sample: plain floats
            _, jac = self._responses(x)
            return jac
        x = np.asarray(x, dtype=float)
        r, k = self.constants.receiver, self.power_gain
        az, el = self.constants.layout.angles(x)
        az, el = az[..., None] + self._offsets, el[..., None] + self._tilts
        jac = np.zeros(x.shape[:-1] + (self.n_output, 4))
        if self.constants.link is None:  # the bench: azimuth only (head_power)
            jac[..., 0] = k * slope(az, r)
        else:
            jac[..., 0] = k * slope(az, r) * receiver_response(el, r)
            jac[..., 1] = k * receiver_response(az, r) * slope(el, r)
        return jac * self.channel_gains[:, None]

    def _responses(self, x) -> tuple[list, np.ndarray]:
        """h and its Jacobian at one state, in plain floats (the per-step path: the
        same formulas as :func:`head_power` and :meth:`h_jacobian`)."""
        key = az, el = self.constants.layout.angles(x).tolist()
        if self._last is not None and self._last[0] == key:  # h, then its Jacobian
            return self._last[1], self._last[2].copy()
        r, k, cone = self.constants.receiver, self.power_gain, self._cone
        powers, jac = [], np.zeros((self.n_output, 4))
        for i, (offset, tilt) in enumerate(self._directions):
            u1, u2, e1, e2 = response_terms(az + offset, r, math.exp)
            g_az, s_az = e1 + e2, response_slope(u1, u2, e1, e2, r)
            if cone:
                u1, u2, e1, e2 = response_terms(el + tilt, r, math.exp)
                g_el, s_el = e1 + e2, response_slope(u1, u2, e1, e2, r)
            else:
                g_el, s_el = 1.0, 0.0
            gain = k * self._gains[i]
            powers.append(gain * g_az * g_el)
            jac[i, 0], jac[i, 1] = gain * s_az * g_el, gain * g_az * s_el
        self._last = (key, powers, jac.copy())
        return powers, jac

    # -- fitted to the world ---------------------------------------------------------

    @classmethod
    def fit(cls, world: LinkWorld, n: int = 2000, seed: int = 0, u_max: float = 20.0,
            noise_scale: float = 1.0, home=(0.0, 0.0)) -> HeadModel:
        """Least squares on ``n`` random one-step transitions of ``world`` (a pan-tilt
        head, its hull at rest at home), each axis at a random angle and rate in the
        box and a random input within +-``u_max`` [rad/s^2]; the gain from its sensor's
        noise-free powers over the box. ``home``: the encoders' angles [rad] at which
        the boresight looks at the LED (x = home - q; zero for a level LED)."""
        from ledsim.physics.head import to_encoder
        from ledsim.physics.sensor import IrradianceSensor

        c = world.config.constants
        rng = np.random.default_rng(seed)
        inertia = np.array([world.hinge_inertia(axis) for axis in range(2)])
        x = rng.uniform(-0.5, 0.5, size=(n, 4))
        u = rng.uniform(-u_max, u_max, size=(n, 2))
        xn = np.empty_like(x)
        home = np.asarray(home, dtype=float)
        for k in range(n):  # angle = home - q
            world.reset(gimbal_angle=home - x[k, :2], gimbal_rate=-x[k, 2:])
            world.set_torques(-inertia * u[k])
            world.step()
            xn[k] = np.r_[home - world.gimbal_angles, -world.gimbal_rates]
        coef_angle, coef_rate = np.empty((2, 3)), np.empty((2, 3))
        for a in range(2):
            rate = x[:, 2 + a]
            feats = np.stack([rate, u[:, a], np.abs(rate) * rate], axis=1)
            coef_angle[a] = np.linalg.lstsq(feats, xn[:, a] - x[:, a], rcond=None)[0]
            coef_rate[a] = np.linalg.lstsq(feats, xn[:, 2 + a], rcond=None)[0]
        sensor = IrradianceSensor(world, noise=False)
        grid = np.linspace(-0.3, 0.3, 7)
        y, g = [], []
        for pan in grid:
            for tilt in grid:
                # head-frame offsets (-pan, -tilt): the pan's over its gain at home
                world.reset(gimbal_angle=home + to_encoder((pan, tilt), home),
                            gimbal_rate=np.zeros(2))
                y.append(sensor.read(noise=False).power_clean)
                g.append(head_power(1.0, -pan, -tilt, c))
        y, g = np.array(y), np.array(g)
        gain = float((g * y).sum() / (g * g).sum())
        world.reset(gimbal_angle=home, gimbal_rate=np.zeros(2))
        return cls(c, coef_angle, coef_rate, gain, inertia, noise_scale=noise_scale)

