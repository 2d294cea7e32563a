"""Offscreen rendering of the link: MuJoCo frames, the LED beam, and a live overlay.

``MUJOCO_GL`` must be chosen before ``mujoco`` is imported: :mod:`ledsim.physics` sets
the default ``osmesa``, and ``ledsim render --gl`` sets it before any import. What a
frame shows:

- the AUV, the gimbal and the transmitter in a fogged, water-tinted scene;
- one beam per photodiode from the LED: cyan with an opacity that follows the received
  power, cut short and turned red where a body blocks it;
- orange arrows above the yoke for the thrusters' surge, sway and heave effort (2 mm
  per newton, from a point the side camera sees);
- a panel with the time, true vs estimated phi, the two powers, and a line on the
  vehicle: IMU on or off, the hull's offset and heading, the thrust;
- on a physical link (:mod:`ledsim.physics.sea_render`), the beam's cone dimmed by the
  water, the surface with its waves, fog from the water's attenuation, and a docking
  station under the LED (:mod:`ledsim.physics.sea_scene`).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import mujoco
import numpy as np

from ledsim.errors import LedsimError
from ledsim.files.outputs import INTERRUPTED, umask
from ledsim.physics.overlay import Overlay
from ledsim.physics.sea_render import add_beam_cone, add_surface
from ledsim.physics.sensor import SensorReading
from ledsim.physics.world import LinkWorld
from ledsim.radiometry.optics import peak_power

BEAM_WIDTH = 0.0012  # m, radius of the drawn beam capsules
CLEAR = np.array([0.35, 1.0, 0.95])
BLOCKED = np.array([1.0, 0.25, 0.15])


class RenderError(LedsimError):
    """Rendering cannot start (bad size, no OpenGL backend)."""


def check_size(world: LinkWorld, width: int, height: int) -> None:
    vis = world.model.vis.global_
    for name, value, limit in (("width", width, vis.offwidth), ("height", height,
                                                               vis.offheight)):
        if not 0 < value <= limit:
            raise RenderError(f"--{name} {value} is not allowed: must be in 1..{limit} "
                              "(the scene's offscreen buffer)")
        if value % 2:
            raise RenderError(f"--{name} {value} is not allowed: H.264 needs an even size")


def make_renderer(world: LinkWorld, width: int, height: int) -> mujoco.Renderer:
    """A ``mujoco.Renderer``; a missing GL library becomes a one-line RenderError."""
    check_size(world, width, height)
    try:
        renderer = mujoco.Renderer(world.model, height=height, width=width)
    except Exception as exc:  # the GL backend failed to load or create a context
        backend = os.environ.get("MUJOCO_GL", "default")
        hint = ("install libosmesa6 (apt-get install libosmesa6)" if backend == "osmesa"
                else "install libegl1 and a GPU driver, or use --gl osmesa")
        raise RenderError(f"cannot start {backend} rendering ({type(exc).__name__}: "
                          f"{str(exc).strip().splitlines()[0] if str(exc).strip() else ''}): "
                          f"{hint}") from None
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = True
    return renderer


def scene_option() -> mujoco.MjvOption:
    """What a frame shows: every geom group up to the optics (group 3: lenses, LED
    housing; the light rays ignore it, the eye does not), and no sites (the lenses
    mark the photodiodes)."""
    opt = mujoco.MjvOption()
    opt.geomgroup[:4] = 1
    opt.sitegroup[:] = 0
    return opt


def add_beams(scene: mujoco.MjvScene, world: LinkWorld, reading: SensorReading,
              blocked_at: list[np.ndarray | None], peak_power: float) -> None:
    """Append one capsule per photodiode from the LED towards it (or to the blocker)."""
    led = world.led_pos.copy()
    for i in range(2):
        if scene.ngeom >= scene.maxgeom:
            return
        end = world.photodiode_pos(i).copy() if blocked_at[i] is None else blocked_at[i]
        level = float(np.clip(reading.power_clean[i] / peak_power, 0.0, 1.0))
        if blocked_at[i] is None:
            rgba = np.r_[CLEAR, 0.15 + 0.7 * level]
        else:
            rgba = np.r_[BLOCKED, 0.85]
        geom = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3),
                            np.eye(3).ravel(), rgba.astype(np.float32))
        mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, BEAM_WIDTH, led, end)
        geom.emission = 0.8
        scene.ngeom += 1


THRUST = np.array([1.0, 0.55, 0.1, 0.9])  # colour of the thrust arrows


def add_thrust_arrows(scene: mujoco.MjvScene, world: LinkWorld) -> None:
    """One arrow per linear thruster (surge, sway, heave), 2 mm per newton, from a point
    above the yoke; none for a thruster at rest."""
    R = world.hull_rotation
    origin = world.hull_pos + R @ np.array([0.8, 0.0, 0.05])
    for axis, force in enumerate(world.thrust[:3]):
        if abs(force) < 0.5 or scene.ngeom >= scene.maxgeom:
            continue
        geom = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_ARROW, np.zeros(3), np.zeros(3),
                            np.eye(3).ravel(), THRUST.astype(np.float32))
        tip = origin + R[:, axis] * 0.002 * float(np.clip(force, -60.0, 60.0))
        mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_ARROW, 0.004, origin, tip)
        scene.ngeom += 1


def blocking_points(world: LinkWorld) -> list[np.ndarray | None]:
    """Where the centre ray from each photodiode to the LED is stopped (None: clear)."""
    points = []
    for i in range(2):
        origin = world.photodiode_pos(i).copy()
        vec = world.led_pos - origin
        length = float(np.linalg.norm(vec))
        unit = vec / length
        dist = float(world.cast_rays(origin, unit[None, :], length)[0])
        points.append(origin + dist * unit if 0 <= dist < length else None)
    return points


class VideoWriter:
    """H.264 mp4 through imageio-ffmpeg, written to a temporary name and renamed at the
    end: an interrupted render never leaves a partial file under the final name."""

    def __init__(self, path: Path, fps: float):
        import imageio.v2 as imageio

        self.path = Path(path)
        # A name of its own per writer: two renders to one --out never share it.
        fd, tmp = tempfile.mkstemp(dir=self.path.parent, prefix=f".{self.path.name}.",
                                   suffix=".partial.mp4")
        os.close(fd)
        self.tmp = Path(tmp)
        self.writer = imageio.get_writer(self.tmp, fps=fps, codec="libx264", quality=7,
                                         macro_block_size=2, ffmpeg_log_level="error")
        self.frames = 0

    def append(self, frame: np.ndarray) -> None:
        self.writer.append_data(frame)
        self.frames += 1

    def close(self, keep: bool = True) -> None:
        self.writer.close()
        if keep and INTERRUPTED.is_set():  # a swallowed Ctrl-C: keep nothing
            keep = False
        if keep:
            os.chmod(self.tmp, 0o666 & ~umask())  # mkstemp makes 0600
            os.replace(self.tmp, self.path)
        elif self.tmp.exists():
            self.tmp.unlink()


class FrameRecorder:
    """Renders frames at ``fps`` during a closed-loop run (an ``on_step`` callback);
    ``estimate``: the overlay draws an estimate beside the true phi."""

    def __init__(self, world: LinkWorld, width: int, height: int, fps: float,
                 camera: str, writer: VideoWriter | None = None, label: str = "",
                 estimate: bool = True, waves=()):
        if camera not in world.camera_names():
            raise RenderError(f"--camera {camera!r} is not in the scene: choose from "
                              f"{', '.join(world.camera_names())}")
        self.world = world
        self.renderer = make_renderer(world, width, height)
        self.camera = camera
        self.fps = fps
        self.next_t = 0.0
        self.writer = writer
        self.overlay = Overlay(width, height, sample_period=world.config.constants.Te,
                               label=label, estimate=estimate)
        self.peak = peak_power(world.config.constants)
        self.last_frame: np.ndarray | None = None
        self.option = scene_option()
        #: A physical link's sea: the beam's cone, the surface and these waves on it.
        self.sea = world.config.constants.link is not None
        self.waves = list(waves)

    def __call__(self, t: float, world: LinkWorld, reading: SensorReading, xhat,
                 status: str = "") -> None:
        """Record step ``t`` [s]; ``status``: the link supervisor's "ok", "lost" or
        "scanning", or "dropout" while the gate holds a blocked photodiode ("" when the
        run is not supervised)."""
        layout = world.config.constants.layout
        if layout.n_axes == 2:  # a pan-tilt head: both angles, the data and one pointing
            azimuth, elevation = layout.angles(xhat)
            ref = layout.reference
            self.overlay.names = tuple(layout.photodiodes[i].series.upper()
                                       for i in (ref, ref + 1))
            self.overlay.push(reading.phi, float(azimuth), reading.power[ref],
                              reading.power[ref + 1], reading.elevation, float(elevation))
        else:
            self.overlay.push(reading.phi, float(layout.angle(xhat)), *reading.power)
        self.overlay.status = status
        if t + 1e-9 < self.next_t:
            return
        self.next_t += 1.0 / self.fps
        frame = self.render(t, reading)
        self.last_frame = frame
        if self.writer is not None:
            self.writer.append(frame)

    def render(self, t: float, reading: SensorReading) -> np.ndarray:
        r = self.renderer
        r.update_scene(self.world.data, camera=self.camera, scene_option=self.option)
        add_beams(r.scene, self.world, reading, blocking_points(self.world),
                  self.peak)
        add_thrust_arrows(r.scene, self.world)
        if self.sea:
            add_beam_cone(r.scene, self.world)
            add_surface(r.scene, self.world, self.waves, t)
        frame = r.render()
        return self.overlay.draw(frame, t, self.peak)

    def close(self) -> None:
        self.renderer.close()
