"""One sample of the ray sensor (:class:`~ledsim.physics.sensor.IrradianceSensor`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class SensorReading:
    """One sample of the sensor. Arrays have one entry per photodiode.

    Attributes:
        power: measured photodiode_power with noise [W], shape (n_pd,), in the
            receiver layout's order.
        power_clean: the same without noise [W].
        incidence_angle: signed phi of each photodiode [rad].
        emission_angle: theta of each photodiode [rad].
        distance: LED-photodiode distance [m].
        visible_fraction: share of aperture rays that reach the LED [-].
        phi, phidot: the true state x = (phi, phidot) of the reference photodiode
            [rad, rad/s].
        gimbal_angle, gimbal_rate: the gimbal encoder: hinge angle [rad] and rate [rad/s].
        hull_pos: the AUV's position [m], shape (3,).
        elevation, elevation_rate: on a pan-tilt head, the reference photodiode's
            elevation [rad] and its rate [rad/s], and phidot is its azimuth's rate about
            its own up (:func:`~ledsim.physics.incidence.head_rates`); None on one axis.
    """

    power: np.ndarray
    power_clean: np.ndarray
    incidence_angle: np.ndarray
    emission_angle: np.ndarray
    distance: np.ndarray
    visible_fraction: np.ndarray
    phi: float
    phidot: float
    gimbal_angle: float
    gimbal_rate: float
    hull_pos: np.ndarray
    elevation: float | None = field(default=None, kw_only=True)
    elevation_rate: float | None = field(default=None, kw_only=True)

    @property
    def x(self) -> np.ndarray:
        """The true state of the reference photodiode: (phi [rad], phidot [rad/s]), or
        on a pan-tilt head (azimuth, elevation [rad], their rates [rad/s])."""
        if self.elevation is None:
            return np.array([self.phi, self.phidot])
        return np.array([self.phi, self.elevation, self.phidot, self.elevation_rate])
