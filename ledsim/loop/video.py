"""A closed-loop run rendered to an H.264 mp4: what ``ledsim render`` and ``ledsim demo``
both call."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ledsim.loop.closed_loop import ClosedLoop
from ledsim.loop.run_config import RunConfig
from ledsim.physics.render import FrameRecorder, VideoWriter
from ledsim.physics.world import LinkWorld


@dataclass
class VideoSpec:
    """Frame size [px], frame rate [1/s] and camera of a video."""

    width: int = 640
    height: int = 480
    fps: float = 30.0
    camera: str = "side"


def check_video(cfg: RunConfig, spec: VideoSpec) -> None:
    """Size, camera and GL backend checked before any physics runs (raises RenderError)."""
    FrameRecorder(LinkWorld(cfg.world_config()), spec.width, spec.height, spec.fps,
                  spec.camera).close()


def render_video(cfg: RunConfig, seed: int, out: Path, spec: VideoSpec,
                 still: Path | None = None, progress: bool = False) -> int:
    """Run ``cfg`` with seed ``seed`` and write its video to ``out`` (and the last frame
    to ``still`` as PNG). Returns the number of frames. Nothing is left under ``out`` if
    the run fails or is interrupted."""
    label = (f"{cfg.scenario} | {cfg.estimator} | "
             f"{', '.join(cfg.disturbances) or 'no disturbance'}")
    writer = VideoWriter(out, spec.fps)
    recorder: list[FrameRecorder] = []

    def on_step(run, t):
        if not recorder:
            waves = [d.wave for d in run.disturbances if hasattr(d, "wave")]
            recorder.append(FrameRecorder(run.world, spec.width, spec.height, spec.fps,
                                          spec.camera, writer, label=label, waves=waves))
        status = ""
        if run.supervised:
            d = run.step.decision
            status = ("scanning" if d.acquiring else "lost" if d.lost
                      else "converging" if d.reason == "converging"
                      else "dropout" if run.step.gate.held.any() else "ok")
        w = run.world
        offset = (w.hull_pos - w.initial_hull_pos) * 1e3
        thrust = w.thrust
        recorder[0].overlay.vehicle = (
            f"IMU {'on' if cfg.imu else 'off'} | hull {offset[0]:+.1f}, {offset[1]:+.1f}, "
            f"{offset[2]:+.1f} mm, yaw {w.hull_yaw * 1e3:+.1f} mrad | thrust "
            f"{thrust[0]:+.0f}, {thrust[1]:+.0f}, {thrust[2]:+.0f} N, yaw {thrust[4]:+.1f} N m")
        recorder[0](t, run.world, run.reading, run.step.decision.xhat, status=status)

    ok = False
    try:
        ClosedLoop(cfg, [seed], on_step=on_step).run(progress=progress)
        if still is not None and recorder and recorder[0].last_frame is not None:
            from PIL import Image

            from ledsim.files.outputs import atomic_write_bytes

            frame = recorder[0].last_frame
            atomic_write_bytes(Path(still), lambda tmp: Image.fromarray(frame).save(
                tmp, format="PNG"))
        ok = True
    finally:
        for rec in recorder:
            rec.close()
        writer.close(keep=ok)
    return writer.frames
