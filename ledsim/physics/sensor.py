"""Ray-based LED irradiance sensor for the two photodiodes.

For each photodiode, rays are cast from the photodiode to points on the LED's emitting
aperture (its centre and a ring). The share of rays that reach the LED scales the direct
power (partial blockage); the power itself is eq. (pow-d-theta-phi)
(:func:`ledsim.radiometry.optics.received_power`) evaluated on MuJoCo's poses with the observer
model's constants:

    d     = |LED - photodiode|                                   [m]
    theta = angle(LED axis, photodiode - LED)                    [rad]
    phi   = signed angle(photodiode normal, LED - photodiode)    [rad], about the hinge

Rays ignore geom group 3 (lenses, LED housing) and the gimbal's own body.
"""

from __future__ import annotations

import math

import numpy as np

from ledsim.physics.incidence import (
    head_rates,
    incidence_geometry,
    incidence_rate,
    photodiode_up,
)
from ledsim.physics.line_of_sight import check_line_of_sight
from ledsim.physics.sensor_reading import SensorReading
from ledsim.physics.world import LinkWorld
from ledsim.radiometry.optics import (
    received_power,
    receiver_response_at,
    transmitter_gain,
    transmitter_gain_at,
)
from observer import jit
from observer.noise import MeasurementNoise
from observer.rowops import FLOATS

compiled_sensor = jit.lazy("ledsim.physics.compiled_sensor")
__all__ = ["IrradianceSensor", "SensorReading"]  # SensorReading: its old home


class IrradianceSensor:
    """Two-photodiode power sensor on a :class:`LinkWorld`.

    Args:
        world: the scene.
        seed: seed of the measurement noise.
        noise: add N(0, measurement_noise_var) to each power.
        noise_scale: multiplies the noise standard deviation (x3 disturbance test).
        measurement_noise: the run's noise object (None: the link's at ``noise_scale``);
            :attr:`measurement_noise` either way.
    """

    def __init__(self, world: LinkWorld, seed: int = 0, noise: bool = True,
                 noise_scale: float = 1.0, measurement_noise: MeasurementNoise | None = None,
                 channel_gains=None):
        self.world = world
        #: Each photodiode's responsivity over its nominal [-] (None: all 1): a head's
        #: calibration, which scales what a channel measures, not the light it gets.
        self.channel_gains = None if channel_gains is None else \
            np.asarray(channel_gains, dtype=float)
        self.constants = world.config.constants
        self.rng = np.random.default_rng(seed)
        self.measurement_noise = (self.constants.measurement_noise(noise_scale)
                                  if measurement_noise is None else measurement_noise)
        self.noise_std = self.measurement_noise.std if noise else 0.0
        #: The noise depends on the signal (a physical link's receiver), and is drawn
        #: at each reading's clean powers.
        self.signal_noise = noise and self.measurement_noise.signal_dependent
        self.layout = self.constants.layout
        self._photodiodes = range(self.layout.n_photodiodes)
        self._reference = self.layout.reference
        self._tilted = self.layout.tilted
        self._head = self.layout.n_axes == 2  # a pan-tilt head: its reading's elevation
        n = world.config.n_rays
        ring = max(n - 1, 0)
        angles = 2 * np.pi * np.arange(ring) / max(ring, 1)
        # Aperture sample points in the LED frame (x, y in its plane; z along its axis).
        self._aperture = np.zeros((n, 3))
        self._aperture[1:, 0] = world.config.aperture_radius * np.cos(angles)
        self._aperture[1:, 1] = world.config.aperture_radius * np.sin(angles)
        check_line_of_sight(self)

    def aperture_points(self) -> np.ndarray:
        """World positions of the aperture sample points, shape (n_rays, 3)."""
        w = self.world
        return w.led_pos + self._aperture @ w.led_rotation.T

    def visible_fraction(self, i: int, targets: np.ndarray | None = None) -> float:
        """Share of rays from photodiode ``i`` that reach the LED aperture unblocked."""
        w = self.world
        origin = w.photodiode_pos(i)
        ox, oy, oz = origin.tolist()
        points = (self.aperture_points() if targets is None else targets).tolist()
        # Plain floats for a handful of rays: numpy's per-call cost was 5x the ray cast.
        dirs, lengths = [], []
        for x, y, z in points:
            vx, vy, vz = x - ox, y - oy, z - oz
            n = math.sqrt(vx * vx + vy * vy + vz * vz)
            dirs += (vx / n, vy / n, vz / n)
            lengths.append(n)
        dist = w.cast_rays(origin, np.array(dirs), max(lengths))
        # cast_rays reports -1 for rays that hit nothing before the cutoff.
        blocked = sum(1 for di, n in zip(dist.tolist(), lengths, strict=True)
                      if 0.0 <= di < n)
        return 1.0 - blocked / len(lengths)

    def geometry(self) -> tuple[list, list, list, list]:
        """(d, theta, phi, visible fraction) of each photodiode at the current state
        (:func:`~ledsim.physics.incidence.incidence_geometry` in plain floats: several
        times faster than numpy on 3-vectors)."""
        w = self.world
        led = w.led_pos.tolist()
        axis = w.led_rotation[:, 2].tolist()  # LED axis
        hinge = w.hinge_axis.tolist()
        targets = self.aperture_points()
        dist, theta, phi, vis = [], [], [], []
        for i in self._photodiodes:
            normal = w.photodiode_normal(i).tolist()
            d, t, p = incidence_geometry(FLOATS, led, axis, self._up(normal, hinge),
                                         w.photodiode_pos(i).tolist(), normal)
            dist.append(d)
            theta.append(t)
            phi.append(p)
            vis.append(self.visible_fraction(i, targets))
        return dist, theta, phi, vis

    def clean_power(self, dist, theta, phi, vis) -> np.ndarray:
        """Noise-free powers [W] from the geometry (any matching array shapes)."""
        c = self.constants
        return received_power(transmitter_gain(dist, theta, c), phi, c.receiver, vis)

    def clean_power_at(self, d, theta, phi, vis, o=FLOATS):
        """:meth:`clean_power` of one photodiode in plain floats (the per-step path), or
        with ``o`` :data:`~observer.rowops.ARRAYS` of many worlds' photodiodes, each
        to one's last bit."""
        c = self.constants
        return vis * transmitter_gain_at(d, theta, c, o) * \
            receiver_response_at(phi, c.receiver, o)

    def read(self, noise: bool = True) -> SensorReading:
        """Sample every photodiode at the current MjData state (on the compiled path,
        :mod:`ledsim.physics.compiled_sensor`, to the same bits)."""
        if jit.enabled():
            return self._compiled_read(noise)
        geo = self.geometry()
        clean = np.array([self.clean_power_at(*g) for g in zip(*geo, strict=True)])
        dist, theta, phi, vis = (np.array(v) for v in geo)
        ref, w = self._reference, self.world
        if self.constants.link is not None:  # a real receiver's cone: its elevation too
            clean = clean * self.elevation_response()
        if w.light_gain is not None:  # the light around the receiver (physics.light)
            clean = clean * w.light_gain
        measured = self.calibrated(clean)
        power = self.noisy(measured) if noise else measured + 0.0
        if self._head:
            rate, elevation, elevation_rate = self.head_truth()
            return SensorReading(power, clean, phi, theta, dist, vis, float(phi[ref]), rate,
                                 w.gimbal_angle, w.gimbal_rate, w.hull_pos.copy(),
                                 elevation=elevation, elevation_rate=elevation_rate)
        return SensorReading(power, clean, phi, theta, dist, vis, float(phi[ref]),
                             self.incidence_rate(ref), w.gimbal_angle, w.gimbal_rate,
                             w.hull_pos.copy())

    def _compiled_read(self, noise: bool) -> SensorReading:
        reader = self.__dict__.get("_reader")
        if reader is None:
            reader = self._reader = compiled_sensor.Reader(self)
        w, ref = self.world, self._reference
        reader.read(self, self.constants.link is not None)
        clean = reader.clean.copy()
        if w.light_gain is not None:
            clean = clean * w.light_gain
        measured = self.calibrated(clean)
        power = self.noisy(measured) if noise else measured + 0.0
        phi = reader.phi.copy()
        fields = (power, clean, phi, reader.theta.copy(), reader.d.copy(),
                  reader.vis.copy(), float(phi[ref]))
        if self._head:
            rate, elevation, elevation_rate = self.head_truth(
                reader.up[ref].tolist(), float(reader.elevation[ref]))
            return SensorReading(*fields, rate, w.gimbal_angle, w.gimbal_rate,
                                 w.hull_pos.copy(), elevation=elevation,
                                 elevation_rate=elevation_rate)
        return SensorReading(*fields, self.incidence_rate(ref), w.gimbal_angle,
                             w.gimbal_rate, w.hull_pos.copy())

    def calibrated(self, clean: np.ndarray) -> np.ndarray:
        """What the channels put out for the light ``clean`` [W] they get: times their
        :attr:`channel_gains` (as it is without)."""
        return clean if self.channel_gains is None else clean * self.channel_gains

    def noisy(self, clean: np.ndarray) -> np.ndarray:
        """The measured powers [W] of the clean powers ``clean`` [W]: this reading's
        noise drawn from :attr:`rng`, and the ambient light's watts."""
        if self.signal_noise:
            power = self.measurement_noise.measure(clean, self.rng)
        else:
            power = clean + self.rng.standard_normal(len(clean)) * self.noise_std
        if self.world.light_noise is not None:
            power = power + self.world.light_noise
        return power

    def _up(self, normal: list, hinge: list) -> list:
        """The axis a photodiode's azimuth is about: the hinge's, or on a tilted head
        the photodiode's own up (:func:`~ledsim.physics.incidence.photodiode_up`)."""
        return list(photodiode_up(FLOATS, normal, hinge)) if self._tilted else hinge

    def elevation(self) -> np.ndarray:
        """Each photodiode's LED elevation out of its turning plane [rad]: the angle
        between the line of sight and the plane normal to the hinge axis, which a
        one-axis gimbal cannot turn to (on a tilted head, the plane normal to the
        photodiode's own up: its elevation, which the tilt turns)."""
        w = self.world
        if self._tilted:
            return np.array(self._tilted_elevation())
        h = w.hinge_axis
        out = []
        for i in self._photodiodes:
            v = w.led_pos - w.photodiode_pos(i)
            out.append(math.asin(max(-1.0, min(1.0, float(v @ h) / math.sqrt(float(v @ v))))))
        return np.array(out)

    def _tilted_elevation(self) -> list[float]:
        """:meth:`elevation` on a tilted head, in plain floats (each photodiode's up)."""
        w = self.world
        hinge, led = w.hinge_axis.tolist(), w.led_pos.tolist()
        out = []
        for i in self._photodiodes:
            ux, uy, uz = self._up(w.photodiode_normal(i).tolist(), hinge)
            px, py, pz = w.photodiode_pos(i).tolist()
            vx, vy, vz = led[0] - px, led[1] - py, led[2] - pz
            sine = (vx * ux + vy * uy + vz * uz) / math.sqrt(vx * vx + vy * vy + vz * vz)
            out.append(math.asin(max(-1.0, min(1.0, sine))))
        return out

    def elevation_response(self) -> np.ndarray:
        """The physical receiver's response at the elevation (its field of view is a
        cone, the same Gaussian across the hinge as about it) [-]; the paper's bench
        measures only about the hinge (1)."""
        return np.array([receiver_response_at(e, self.constants.receiver)
                         for e in self.elevation()])

    def head_truth(self, up: list | None = None, elevation: float | None = None
                   ) -> tuple[float, float, float]:
        """On a pan-tilt head, the reference photodiode's azimuth rate [rad/s],
        elevation [rad] and elevation rate [rad/s]
        (:func:`~ledsim.physics.incidence.head_rates`); ``up`` and ``elevation``: its up
        and elevation where the caller has them (the compiled reading)."""
        w, i = self.world, self._reference
        normal = w.photodiode_normal(i).tolist()
        if up is None:
            up = self._up(normal, w.hinge_axis.tolist())
        az_rate, el_rate = head_rates(FLOATS, (w.led_pos - w.photodiode_pos(i)).tolist(),
                                      w.photodiode_velocity(i).tolist(),
                                      w.transmitter_velocity.tolist(), up, normal)
        if elevation is None:
            elevation = self._tilted_elevation()[i]
        return az_rate, elevation, el_rate

    def incidence_rate(self, i: int) -> float:
        """d(phi_i)/dt [rad/s]: line-of-sight rotation minus photodiode rotation, about the
        hinge axis (:func:`~ledsim.physics.incidence.incidence_rate`)."""
        w = self.world
        return incidence_rate((w.led_pos - w.photodiode_pos(i)).tolist(),
                              w.photodiode_velocity(i).tolist(),
                              w.transmitter_velocity.tolist(), w.hinge_axis.tolist())
