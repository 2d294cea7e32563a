"""The sensor of every world of a :class:`~ledsim.physics.batch.WorldBatch` in one pass.

It stays ray-based where it matters: a light-blocking geom (groups 0-2, not the gimbal)
can only stop a ray from a photodiode to the LED aperture if its bounding sphere comes
within reach of that segment. Where none does, the line of sight is provably clear and
the visible fraction is 1; only the (world, photodiode) pairs with a geom that close cast
their rays (``mj_multiRay``, through the world's own sensor, exactly as a single run
does).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ledsim.physics.batch import WorldBatch, WorldPoses, cross3, dot3
from ledsim.physics.sensor import IrradianceSensor, SensorReading
from ledsim.radiometry.optics import received_power, receiver_response, transmitter_gain


@dataclass
class BatchReading(SensorReading):
    """One sample of N sensors: the fields of :class:`SensorReading` with a leading axis
    of N worlds (``phi``, ``phidot``, ``gimbal_angle``, ``gimbal_rate``: (N,)), and

    Attributes:
        rays: (N, n_pd) which photodiodes cast rays this step (the others were provably clear).
    """

    rays: np.ndarray


def segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance [m] from each point (..., G, 3) to the segment a-b (..., 3)."""
    ab = (b - a)[..., None, :]
    ap = points - a[..., None, :]
    s = np.clip(dot3(ap, ab) / np.maximum(dot3(ab, ab), 1e-300), 0.0, 1.0)
    return np.linalg.norm(ap - s[..., None] * ab, axis=-1)


def needs_rays(poses: WorldPoses, aperture_radius: float,
               margin: float = 1e-6) -> np.ndarray:
    """(N, n_pd): which photodiodes of the worlds of ``poses`` have a light-blocking
    geom within reach of their line of sight to the LED aperture (of radius
    ``aperture_radius`` [m]): its bounding sphere within the aperture radius (plus
    ``margin`` [m]) of the segment photodiode-LED, or a plane that close to either end.
    Elsewhere the line of sight is provably clear: no ray can be stopped."""
    b = poses
    n, npd = len(b.worlds), b.n_photodiodes
    if b.unbounded:
        return np.ones((n, npd), dtype=bool)
    out = np.zeros((n, npd), dtype=bool)
    led, pds = b.led_pos, b.photodiode_pos
    if b.planes.size:
        normal = b.plane_normal
        led_side = dot3(led[:, None] - b.plane_pos, normal)  # (N, P)
        for i in range(npd):
            pd_side = dot3(pds[:, None, i] - b.plane_pos, normal)
            out[:, i] = np.any(np.minimum(pd_side, led_side)
                               <= aperture_radius + margin, axis=1)
    if b.blocking_geoms.size == 0:
        return out
    centres = b.geom_pos
    reach = b.rbound + aperture_radius + margin  # (G,)
    # Coarse pass: both segments lie in the ball around the LED through the farther
    # photodiode; only geoms that reach into it get the exact segment test.
    radius = np.sqrt(np.max(dot3(pds - led[:, None], pds - led[:, None]), axis=1))
    gap = centres - led[:, None]
    near = np.sqrt(dot3(gap, gap)) <= radius[:, None] + reach
    worlds, geoms = np.nonzero(near)
    if worlds.size:
        for i in range(npd):
            dist = segment_distance(centres[worlds, geoms][:, None],
                                    pds[worlds, i], led[worlds])[:, 0]
            np.logical_or.at(out[:, i], worlds, dist <= reach[geoms])
    return out


class BatchSensor:
    """The photodiodes' sensor of every world of a :class:`WorldBatch` in one pass.

    Args:
        batch: the worlds.
        sensors: each world's :class:`IrradianceSensor` (its seed, noise and rays).
        steps: control steps the run will take (the noise is drawn up front from each
            sensor's generator: the same numbers, in the same order, as step by step).
        margin: extra clearance [m] required before a line of sight counts as clear.
    """

    def __init__(self, batch: WorldBatch, sensors: Sequence[IrradianceSensor], steps: int,
                 margin: float = 1e-6):
        self.batch = batch
        self.sensors = list(sensors)
        w0 = batch.worlds[0]
        self.constants = w0.config.constants
        self.aperture_radius = w0.config.aperture_radius
        self.margin = margin
        npd = batch.n_photodiodes
        self.signal_noise = self.sensors[0].signal_noise
        # Drawn up front, scaled now (the paper's) or at each reading's signal.
        self.noise = np.stack([s.rng.standard_normal((steps, npd))
                               * (1.0 if self.signal_noise else s.noise_std)
                               for s in self.sensors], axis=1)  # (steps, N, n_pd)
        self.k = 0

    def needs_rays(self) -> np.ndarray:
        """(N, n_pd): :func:`needs_rays` of the batch."""
        return needs_rays(self.batch, self.aperture_radius, self.margin)

    def clean(self) -> tuple[np.ndarray, ...]:
        """(clean power [W], phi [rad], theta [rad], distance [m], visible fraction,
        rays cast), each (N, n_pd), of every world at the current state, without noise."""
        b, c = self.batch, self.constants
        v = b.led_pos[:, None, :] - b.photodiode_pos  # (N, n_pd, 3)
        dist = np.sqrt(dot3(v, v))
        u = v / dist[..., None]
        normal = b.photodiode_normal
        axis = b.led_axis[:, None, :]
        hinge = b.hinge_axis[:, None, :]
        if self.constants.layout.tilted:  # each photodiode's own up (incidence.py)
            hinge = hinge - dot3(hinge, normal)[..., None] * normal
            hinge = hinge / np.sqrt(dot3(hinge, hinge))[..., None]
        phi = np.arctan2(dot3(cross3(normal, u), hinge), dot3(normal, u))
        theta = np.arccos(np.clip(-dot3(axis, u), -1.0, 1.0))
        rays = self.needs_rays()
        vis = np.ones_like(dist)
        for n, i in zip(*np.nonzero(rays), strict=True):
            s = self.sensors[n]
            vis[n, i] = s.visible_fraction(int(i), s.aperture_points())
        clean = received_power(transmitter_gain(dist, theta, c), phi, c.receiver, vis)
        if c.link is not None:  # a real receiver's cone: the elevation costs power too
            sine = np.maximum(np.minimum(dot3(u, hinge), 1.0), -1.0)  # np.clip: 2x slower
            clean = clean * receiver_response(np.arcsin(sine), c.receiver)
        return clean, phi, theta, dist, vis, rays

    def read(self) -> BatchReading:
        """Sample every world's photodiodes at the current state (then the next step's
        noise is used)."""
        b = self.batch
        clean, phi, theta, dist, vis, rays = self.clean()
        worlds = [s.world for s in self.sensors]
        lit = any(w.light_gain is not None or w.light_noise is not None for w in worlds)
        if lit:  # the light around the receiver (ledsim.physics.light)
            clean = clean * np.stack([np.ones(clean.shape[1]) if w.light_gain is None
                                      else w.light_gain for w in worlds])
        measured = clean
        if any(s.channel_gains is not None for s in self.sensors):  # each head's calibration
            measured = np.stack([s.calibrated(row) for s, row in zip(self.sensors, clean,
                                                                     strict=True)])
        if self.signal_noise:
            power = self.sensors[0].measurement_noise.measure_with(self.noise[self.k],
                                                                   measured)
        else:
            power = measured + self.noise[self.k]
        if lit:
            power = power + np.stack([np.zeros(clean.shape[1]) if w.light_noise is None
                                      else w.light_noise for w in worlds])
        self.k += 1
        return BatchReading(power, clean, phi, theta, dist, vis, phi[:, b.reference].copy(),
                            self.incidence_rate0(), b.qpos_hinge.copy(),
                            b.qvel_hinge.copy(), b.hull_pos.copy(), rays)

    def incidence_rate0(self) -> np.ndarray:
        """d(phi)/dt of the reference photodiode of every world [rad/s]
        (:meth:`IrradianceSensor.incidence_rate`)."""
        b = self.batch
        ang, lin = b.photodiode_velocity0()
        los = b.led_pos - b.site_pos[:, b.reference]
        rel = b.transmitter_velocity - lin
        d2 = dot3(los, los)
        los_rate = dot3(cross3(los, rel), b.hinge_axis) / d2
        return los_rate - dot3(ang, b.hinge_axis)

