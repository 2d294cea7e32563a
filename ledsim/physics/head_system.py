"""A pan-tilt head's MuJoCo world seen through the observer's system interface: what
:class:`~ledsim.physics.gimbal_system.GimbalSystem` is for the paper's one axis.

=======  ==========================================================  =======
symbol   meaning                                                     unit
=======  ==========================================================  =======
x[0:2]   the data detector's azimuth and elevation of the LED         rad
x[2:4]   their rates                                                 rad/s
u        commanded angular acceleration of each angle                rad/s^2
y        each photodiode's noise-free power                          W
=======  ==========================================================  =======

Each angle is its home value less its encoder's (``x = home - q`` near the boresight,
:data:`~ledsim.physics.layout.ELEVATION`), and a torque tau gives angle'' = -tau / I on
both hinges. :attr:`HeadSystem.home` is the encoders' pointing at the LED, found from the
scene (an LED deeper or shallower than the receiver stands at an elevation). ``f`` and
``h`` step and read the world itself; the estimators compute with
:class:`~ledsim.physics.head_model.HeadModel`, fitted to it (:meth:`HeadSystem.model`).
"""

from __future__ import annotations

import numpy as np

from ledsim.physics.gimbal_system import world_metadata
from ledsim.physics.head import to_encoder
from ledsim.physics.head_model import HeadModel
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld, WorldConfig
from ledsim.radiometry.optics import plausible_power_range
from observer.system import DiscreteSystem


class HeadSystem(DiscreteSystem):
    """:class:`DiscreteSystem` whose f and h are a pan-tilt head's MuJoCo world and its
    ray sensor (the module's text gives the state)."""

    n_state = 4
    n_input = 2
    state_names = ("azimuth [rad]", "elevation [rad]", "azimuth rate [rad/s]",
                   "elevation rate [rad/s]")

    def __init__(self, config: WorldConfig, domain: tuple[float, float] = (0.5, 0.5)):
        layout = config.constants.layout
        if layout.n_axes != 2:
            raise ValueError(f"a head system needs a layout of two axes, not "
                             f"{layout.n_axes}")
        self.config = config
        self.world = LinkWorld(config)
        self.sensor = IrradianceSensor(self.world, noise=False)
        c = self.constants = config.constants
        self.n_output = layout.n_photodiodes
        self.output_names = tuple(f"{p.series} [W]" for p in layout.photodiodes)
        angle_noise, rate_noise = np.asarray(c.process_noise_std, dtype=float)
        self.set_model(c.Te, [domain[0]] * 2 + [domain[1]] * 2,
                       [angle_noise] * 2 + [rate_noise] * 2, c.measurement_noise(),
                       plausible_power_range(c))
        self.inertia = np.array([self.world.hinge_inertia(a) for a in range(2)])
        self.home = self._pointing()
        #: the one-axis name of the home (``GimbalSystem.phi_home``): per axis here
        self.phi_home = self.home
        self.world.reset(gimbal_angle=self.home, gimbal_rate=np.zeros(2))

    def _pointing(self, iterations: int = 8) -> np.ndarray:
        """The encoders' angles [rad] at which the data detector looks at the LED: x is
        home - q to first order (the pan's share over its gain, ``head.to_encoder``), so
        each pass adds the angles it still reads."""
        q = np.zeros(2)
        for _ in range(iterations):
            self.world.reset(gimbal_angle=q, gimbal_rate=np.zeros(2))
            q = q + to_encoder(self.sensor.read(noise=False).x[:2], q)
        return q

    def torque_for(self, u) -> np.ndarray:
        """Each motor's torque [N m] that commands angular acceleration ``u`` [rad/s^2]
        of its angle."""
        return -self.inertia * np.asarray(u, dtype=float)

    def _set_state(self, x) -> None:
        """The head at the state ``x`` (head-frame angles and rates) from its home."""
        self.world.reset(gimbal_angle=self.home - to_encoder(x[:2], self.home),
                         gimbal_rate=-to_encoder(x[2:], self.home))

    def f(self, x, u=0.0):
        x = np.asarray(x, dtype=float)
        batch = x.reshape(-1, 4)
        torques = self.torque_for(self.input_array(u, x.shape[:-1])).reshape(-1, 2)
        out = np.empty_like(batch)
        for k, (xk, tau) in enumerate(zip(batch, torques, strict=True)):
            self._set_state(xk)
            self.world.set_torques(tau)
            self.world.step()
            out[k] = self.sensor.read(noise=False).x
        return out.reshape(x.shape)

    def h(self, x):
        x = np.asarray(x, dtype=float)
        batch = x.reshape(-1, 4)
        out = np.empty((len(batch), self.n_output))
        for k, xk in enumerate(batch):
            self._set_state(xk)
            out[k] = self.sensor.read(noise=False).power_clean
        return out.reshape(x.shape[:-1] + (self.n_output,))

    def model(self, noise_scale: float = 1.0) -> HeadModel:
        """The four-state model fitted to this world (about its :attr:`home`)."""
        return HeadModel.fit(self.world, home=self.home, noise_scale=noise_scale)

    def metadata(self) -> dict:
        meta = super().metadata()
        meta["constants"] = self.constants.to_dict()
        meta["world"] = world_metadata(self.config, self.inertia.tolist(),
                                       home=self.home.tolist())
        return meta
