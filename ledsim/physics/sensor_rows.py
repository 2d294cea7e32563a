"""The ray sensors of many worlds read in one pass, each world's reading to the last bit
what its own :class:`~ledsim.physics.sensor.IrradianceSensor` reads alone.

The poses come from every world's ``MjData`` in one gather
(:class:`~ledsim.physics.batch.WorldPoses`); the geometry and the powers are the row
kernels the single sensor runs in plain floats (:mod:`ledsim.physics.incidence`,
:meth:`~ledsim.physics.sensor.IrradianceSensor.clean_power_at`)
run over arrays with libm's functions per element (:data:`observer.rowops.ARRAYS`).
Rays are cast only for the photodiodes that a light-blocking geom could shadow
(:func:`~ledsim.physics.batch_sensor.needs_rays`): elsewhere no ray can be stopped, and
the visible fraction is the 1 the rays would give. Each world draws its noise from its
own sensor's generator, in the order a reading alone takes it.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from ledsim.physics.batch import WorldPoses
from ledsim.physics.batch_sensor import needs_rays
from ledsim.physics.incidence import incidence_geometry, incidence_rate, photodiode_up
from ledsim.physics.sensor import IrradianceSensor, SensorReading
from observer.rowops import ARRAYS

_SITE = mujoco.mjtObj.mjOBJ_SITE


class SensorRows:
    """The sensors of N worlds, read together.

    Args:
        sensors: one :class:`IrradianceSensor` per world (the worlds of one model
            layout). With one, :meth:`read` is that sensor's own reading.

    :attr:`sensors` may be changed in place (a world restarted with a fresh sensor).
    """

    def __init__(self, sensors: Sequence[IrradianceSensor]):
        self.sensors = list(sensors)
        if not self.sensors:
            raise ValueError("at least one sensor")
        self.worlds = [s.world for s in self.sensors]
        self.poses = WorldPoses(self.worlds) if len(self.sensors) > 1 else None
        s0 = self.sensors[0]
        self.constants = s0.constants
        self.reference = s0.layout.reference
        self._tilted = s0.layout.tilted
        self._head = s0.layout.n_axes == 2
        self._radius = self.worlds[0].config.aperture_radius
        self._velocity = np.empty((len(self.sensors), 6))
        w0 = self.worlds[0]
        self._reference_site = w0.ids.photodiode_sites[self.reference]

    def read(self) -> list[SensorReading]:
        """Every world's :meth:`IrradianceSensor.read` at its current state."""
        if self.poses is None:
            return [self.sensors[0].read()]
        p, c, o = self.poses, self.constants, ARRAYS
        p.gather()
        led, axis, hinge = p.led_pos.T, p.led_axis.T, p.hinge_axis.T
        pds, normals = p.photodiode_pos, p.photodiode_normal
        rays = needs_rays(p, self._radius)
        columns = []  # (d, theta, phi, visible fraction) of each photodiode, (N,) each
        for i in range(p.n_photodiodes):
            normal = normals[:, i].T
            up = photodiode_up(o, normal, hinge) if self._tilted else hinge
            d, theta, phi = incidence_geometry(o, led, axis, up, pds[:, i].T, normal)
            vis = np.ones(len(self.worlds))
            for n in np.flatnonzero(rays[:, i]).tolist():
                s = self.sensors[n]
                vis[n] = s.visible_fraction(i, s.aperture_points())
            columns.append((d, theta, phi, vis))
        dist, theta, phi, vis = (np.stack(q, axis=1) for q in zip(*columns, strict=True))
        clean = self.sensors[0].clean_power_at(dist, theta, phi, vis, o)
        rates = self._reference_rates()
        # The encoders and hulls as the gather read them (each world's own values).
        angles, speeds, hulls = p.qpos_hinge.tolist(), p.qvel_hinge.tolist(), p.hull_pos.copy()
        readings = []
        if self._head:  # each world's own head's truth, as its sensor reads it alone
            return [self._head_reading(n, s, clean[n], phi, theta, dist, vis, angles, speeds,
                                       hulls) for n, s in enumerate(self.sensors)]
        for n, s in enumerate(self.sensors):
            w = s.world
            row = clean[n]
            if c.link is not None:  # a real receiver's cone: its elevation too
                row = row * s.elevation_response()
            if w.light_gain is not None:
                row = row * w.light_gain
            power = s.noisy(s.calibrated(row))
            readings.append(SensorReading(power, row, phi[n], theta[n], dist[n], vis[n],
                                          float(phi[n, self.reference]), float(rates[n]),
                                          angles[n], speeds[n], hulls[n]))
        return readings

    def _head_reading(self, n, s, row, phi, theta, dist, vis, angles, speeds, hulls):
        """World ``n``'s reading on a pan-tilt head (its truth by
        :meth:`IrradianceSensor.head_truth`)."""
        w, c = s.world, self.constants
        if c.link is not None:
            row = row * s.elevation_response()
        if w.light_gain is not None:
            row = row * w.light_gain
        rate, elevation, elevation_rate = s.head_truth()
        return SensorReading(s.noisy(s.calibrated(row)), row, phi[n], theta[n], dist[n],
                             vis[n], float(phi[n, self.reference]), rate, angles[n],
                             speeds[n], hulls[n], elevation=elevation,
                             elevation_rate=elevation_rate)

    def _reference_rates(self) -> np.ndarray:
        """:meth:`IrradianceSensor.incidence_rate` of each world's reference photodiode."""
        p, v = self.poses, self._velocity
        for n, w in enumerate(self.worlds):
            mujoco.mj_objectVelocity(w.model, w.data, _SITE, self._reference_site, v[n], 0)
        sight = (p.led_pos - p.photodiode_pos[:, self.reference]).T
        return incidence_rate(sight, v.T, p.transmitter_velocity.T, p.hinge_axis.T)
