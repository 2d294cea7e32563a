"""What a frame of a physical link adds to the bench's (:mod:`ledsim.physics.render`):
the LED's beam as a cone that the water dims, and the sea's surface with its waves
above the vehicles. Both are drawn into the frame's scene only (``mjvGeom``s), so the
physics and the light rays never meet them."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ledsim.physics.linear_waves import RegularWave
from ledsim.physics.world import LinkWorld

CONE = np.array([0.35, 1.0, 0.95])
SURFACE = np.array([0.55, 0.8, 0.9])
CONE_SLICES = 40
SURFACE_TILES = 24  # per side


def _frame(axis: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is ``axis`` (3x3, row-major flattened)."""
    z = axis / np.linalg.norm(axis)
    helper = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1).ravel()


def _add(scene: mujoco.MjvScene, kind, size, pos, mat, rgba, emission: float = 0.0) -> bool:
    if scene.ngeom >= scene.maxgeom:
        return False
    geom = scene.geoms[scene.ngeom]
    mujoco.mjv_initGeom(geom, kind, np.asarray(size, float), np.asarray(pos, float),
                        np.asarray(mat, float), np.asarray(rgba, np.float32))
    geom.emission = emission
    scene.ngeom += 1
    return True


def add_beam_cone(scene: mujoco.MjvScene, world: LinkWorld) -> None:
    """The LED's beam out to the receiver: discs across its half-power cone, fading as
    exp(-c s) with the water's beam attenuation c."""
    c = world.config.constants
    axis = world.led_rotation[:, 2]
    length = 1.05 * c.distance
    spread = math.tan(c.led_half_angle)
    atten = c.link.water_at_led.attenuation if c.link is not None else 0.0
    mat = _frame(axis)
    for i in range(CONE_SLICES):
        s = (i + 0.5) / CONE_SLICES * length
        alpha = 0.05 * math.exp(-atten * s)
        _add(scene, mujoco.mjtGeom.mjGEOM_CYLINDER, [s * spread, 0.5 * length / CONE_SLICES
                                                      * 0.05, 0.0],
             world.led_pos + s * axis, mat, np.r_[CONE, alpha], emission=0.6)


def add_surface(scene: mujoco.MjvScene, world: LinkWorld, waves: list[RegularWave],
                t: float) -> None:
    """The still surface at the receiver's depth, lifted and tilted by the waves: a grid
    of thin tiles over the link."""
    c = world.config.constants
    centre = world.link_midpoint()
    half = max(20.0, 0.8 * c.distance)
    step = 2 * half / SURFACE_TILES
    level = float(world.initial_hull_pos[2]) + world.config.depth
    grid = (np.arange(SURFACE_TILES) + 0.5) * step - half
    xs, ys = np.meshgrid(centre[0] + grid, centre[1] + grid, indexing="ij")
    points = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
    eta = np.zeros(len(points))
    slope = np.zeros((len(points), 2))
    for wave in waves:
        eta += wave.elevation(points, t)
        # d(eta)/d(xi) = -a k sin(theta), along the wave's heading
        g = -0.5 * wave.height * wave.k * np.sin(wave.phase(points, t))
        slope += g[:, None] * [math.cos(wave.heading), math.sin(wave.heading)]
    for p, z, (sx, sy) in zip(points, eta, slope, strict=True):
        normal = np.array([-sx, -sy, 1.0])
        if not _add(scene, mujoco.mjtGeom.mjGEOM_BOX, [0.52 * step, 0.52 * step, 0.005],
                    [p[0], p[1], level + z], _frame(normal), np.r_[SURFACE, 0.5],
                    emission=0.5):
            return
