
import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.physics.render import FrameRecorder, RenderError, check_size
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld

HINGE = np.array([0.89, 0.0, 0.0])


@pytest.fixture(scope="module")
def recorder():
    world = LinkWorld()
    world.reset(0.1)
    rec = FrameRecorder(world, 320, 240, 30, "side")
    yield rec
    rec.close()


def frame_at(rec, occluded: bool, beams: bool = True):
    world = rec.world
    world.set_occluder(world.link_midpoint() if occluded else world.occluder_home)
    world.forward_kinematics()
    reading = IrradianceSensor(world).read()
    rec.overlay.push(reading.phi, reading.phi, *reading.power)
    if not beams:  # the same scene without the beam capsules
        rec.renderer.update_scene(world.data, camera=rec.camera, scene_option=rec.option)
        return rec.renderer.render()
    return rec.render(0.0, reading)


def beam_pixels(frame, bare):
    """(red, cyan) pixels the beams add to the scene ``bare`` (above the overlay)."""
    rows = int(0.7 * frame.shape[0])
    scene = frame[:rows]
    r, g, b = (scene[..., i].astype(int) for i in range(3))
    new = np.abs(scene.astype(int) - bare[:rows].astype(int)).sum(axis=-1) > 60
    red = np.count_nonzero(new & (r > 180) & (g < 120) & (b < 120))
    cyan = np.count_nonzero(new & (g > 180) & (b > 170) & (r < 170))
    return red, cyan


def test_frames_render_headless_and_are_not_blank(recorder):
    frame = frame_at(recorder, occluded=False)
    assert frame.shape == (240, 320, 3) and frame.dtype == np.uint8
    assert frame.std() > 10  # not a blank or single-colour image
    recorder.world.reset(0.4)
    other = frame_at(recorder, occluded=False)
    assert np.abs(other.astype(int) - frame.astype(int)).mean() > 0.5  # not constant


def test_beam_turns_red_and_short_when_blocked(recorder):
    recorder.world.reset(0.0)
    red_clear, cyan_clear = beam_pixels(frame_at(recorder, occluded=False),
                                        frame_at(recorder, occluded=False, beams=False))
    red_blocked, cyan_blocked = beam_pixels(frame_at(recorder, occluded=True),
                                            frame_at(recorder, occluded=True, beams=False))
    assert cyan_clear > 20 and red_clear == 0
    assert red_blocked > 5 and cyan_blocked < cyan_clear / 2
    recorder.world.reset(0.0)


@pytest.mark.parametrize("w,h", [(0, 240), (320, -2), (4000, 240), (321, 240)])
def test_bad_sizes_are_refused(w, h):
    with pytest.raises(RenderError):
        check_size(LinkWorld(), w, h)


def test_render_writes_an_mp4_that_decodes_to_the_expected_frames(tmp_path):
    """With MUJOCO_GL unset, as a user runs it: the CLI picks the headless backend."""
    import os

    import imageio.v3 as iio

    out = tmp_path / "clip.mp4"
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    r = run_cli("render", "--seconds", "0.5", "--width", "160", "--height", "120",
                "--fps", "10", "--disturbance", "occlusion:start=0.1,duration=0.2",
                "--out", str(out), env=env)
    assert r.returncode == 0, r.stderr
    frames = iio.imread(out)
    assert frames.shape == (5, 120, 160, 3)  # t = 0, 0.1, 0.2, 0.3, 0.4 s
    assert not list(tmp_path.glob(".*partial*"))


@pytest.mark.parametrize("args,needle,out", [
    (["--width", "0"], "--width 0", "v.mp4"),
    (["--height", "5000"], "--height 5000", "v.mp4"),
    (["--fps", "0"], "--fps", "v.mp4"),
    (["--camera", "nope"], "nope", "v.mp4"),
    (["--scene", "missing.xml"], "does not exist", "v.mp4"),
    ([], "not writable", "no-such-dir/x.mp4"),
    ([], ".mp4", "clip.gif"),
])
def test_render_bad_input_is_one_line_exit_2(tmp_path, args, needle, out):
    target = tmp_path / out
    r = run_cli("render", "--seconds", "0.2", *args, "--out", str(target))
    assert_user_error(r, needle)
    assert not target.exists() and not target.parent.exists() or not any(
        target.parent.iterdir())


def test_missing_gl_library_names_the_fix(monkeypatch):
    """A GL backend that cannot load (as when libOSMesa is absent) gives one clear line."""
    import ledsim.physics.render as render

    def broken(*args, **kwargs):
        raise ImportError("Cannot use OSMesa rendering platform. The PyOpenGL library "
                          "could not find libOSMesa")

    monkeypatch.setattr(render.mujoco, "Renderer", broken)
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    with pytest.raises(RenderError, match="apt-get install libosmesa6") as info:
        render.make_renderer(LinkWorld(), 320, 240)
    assert "\n" not in str(info.value)


def test_overlay_axes_stay_put_and_show_five_seconds():
    from ledsim.physics.overlay import Overlay, axis_limits

    assert axis_limits([], (-0.5, 0.5), 0.5) == (-0.5, 0.5)
    # A 0.03 rad wobble keeps the fixed scale (it used to fill the panel) ...
    assert axis_limits([0.01, 0.04, float("nan")], (-0.5, 0.5), 0.5) == (-0.5, 0.5)
    # ... and the scale widens in whole steps only when the data leaves it.
    assert axis_limits([-1.2, 0.7], (-0.5, 0.5), 0.5) == (-1.5, 1.0)
    # One sample per control step of 10 ms: five seconds of history, not 1.5.
    o = Overlay(320, 240, seconds_shown=5.0, sample_period=0.01)
    for _ in range(1000):
        o.push(0.0, 0.0, 1.0, 0.9)
    assert len(o.phi) == 501
    frame = o.draw(np.zeros((240, 320, 3), np.uint8), 10.0, 1.0)
    assert frame.shape == (240, 320, 3) and frame[-80:].std() > 5
