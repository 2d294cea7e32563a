"""The head a run points when no flag names one (issue 48): the paper's yaw gimbal on its
bench, the pan-tilt with its quad on a physical link, the yaw gimbal where the run asks
for what only it runs (said in one line); and a ``--scene`` whose hinges do not fit the
head, refused in one line."""

import json

import mujoco
import pytest
from conftest import run_cli

from ledsim.errors import LedsimError
from ledsim.files.resources import scene_path
from ledsim.loop.run_config import RunSpec


@pytest.mark.parametrize("kw, head", [
    (dict(), ("yaw", "pair")),
    (dict(link="luma"), ("pan-tilt", "quad")),
    (dict(link="bluecomm-200", estimator="ekf"), ("pan-tilt", "quad")),
    (dict(link="luma", gimbal="yaw"), ("yaw", "pair")),
    (dict(link="luma", receiver="pair"), ("yaw", "pair")),
    (dict(link="luma", estimator="kkl-bank"), ("yaw", "pair")),
    (dict(link="luma", estimator="kkl-scheduled"), ("yaw", "pair")),
    (dict(link="luma", checkpoint="assets/checkpoints/kkl_d0.085.safetensors"),
     ("yaw", "pair")),
])
def test_the_default_head_follows_the_link_and_what_the_run_asks_for(kw, head):
    spec = RunSpec(**kw)
    spec.validate()
    assert spec.world.head == head


def test_a_one_axis_estimator_on_a_physical_link_runs_the_yaw_gimbal_and_says_so(tmp_path):
    r = run_cli("run", "--link", "luma", "--estimator", "kkl-bank", "--seconds", "0.3",
                "--seeds", "1", "--no-plot", "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    notes = [line for line in r.stderr.splitlines() if "runs the yaw gimbal" in line]
    assert len(notes) == 1 and "kkl-bank is one-axis" in notes[0], r.stderr
    assert json.loads((tmp_path / "o" / "results.json").read_text())["gimbal"] == "yaw"
    r = run_cli("run", "--link", "luma", "--gimbal", "yaw", "--estimator", "kkl-bank",
                "--seconds", "0.3", "--seeds", "1", "--no-plot", "--out",
                str(tmp_path / "named"))
    assert r.returncode == 0 and "runs the yaw gimbal" not in r.stderr, r.stderr


def test_the_envs_v0_and_v1_keep_the_yaw_gimbal_on_a_physical_link():
    import gymnasium as gym

    import ledsim.envs  # noqa: F401 (registers the envs)

    for env_id in ("ledsim/LinkAlign-v0", "ledsim/LinkAlign-v1"):
        env = gym.make(env_id, link="luma")
        try:
            assert env.action_space.shape == (1,), env_id
            assert env.unwrapped.cfg.world.head == ("yaw", "pair")
        finally:
            env.close()


def _scene(tmp_path, edit) -> str:
    spec = mujoco.MjSpec.from_file(str(scene_path()))
    edit(spec)
    path = tmp_path / "scene.xml"
    path.write_text(spec.to_xml())
    return str(path)


def _pan_about_x(spec):
    spec.joint("gimbal_hinge").axis = [1.0, 0.0, 0.0]


def _extra_hinge(spec):
    spec.body("gimbal").add_body(name="wobbler", mass=0.01, inertia=[1e-6] * 3).add_joint(
        name="wobble", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])


def _slide(spec):
    spec.joint("gimbal_hinge").type = mujoco.mjtJoint.mjJNT_SLIDE


@pytest.mark.parametrize("edit, gimbal, match", [
    (_pan_about_x, "yaw", r"'gimbal_hinge' turns about \(1.0, 0.0, 0.0\)"),
    (_extra_hinge, "yaw", "a joint 'wobble' that a head of axes azimuth does not turn"),
    (_extra_hinge, "pan-tilt", "'wobble' that a head of axes azimuth, elevation"),
    (_slide, "pan-tilt", "'gimbal_hinge' is a slide joint"),
])
def test_a_scene_whose_hinges_do_not_fit_the_head_is_refused(tmp_path, edit, gimbal, match):
    scene = _scene(tmp_path, edit)
    with pytest.raises(LedsimError, match=match):
        RunSpec(link="luma", gimbal=gimbal, scene=scene).validate()


def test_a_scene_hinge_mismatch_is_one_line_and_exit_2_on_the_command_line(tmp_path):
    scene = _scene(tmp_path, _pan_about_x)
    r = run_cli("run", "--scene", scene, "--seconds", "0.2", "--seeds", "1",
                "--out", str(tmp_path / "o"))
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "gimbal_hinge" in r.stderr
    assert not (tmp_path / "o").exists()


def test_a_saved_config_keeps_its_head_and_an_older_one_reads_as_the_yaw():
    saved = json.loads(json.dumps(RunSpec(link="luma", estimator="ekf").flat()))
    assert saved["gimbal"] == "pan-tilt"  # saved as run
    assert RunSpec.from_dict(saved).world.head == ("pan-tilt", "quad")
    older = {**saved, "gimbal": None, "receiver": None}  # before the default
    assert RunSpec.from_dict(older).world.head == ("yaw", "pair")
    assert RunSpec().flat()["gimbal"] is None  # the bench's saves as before


def test_a_sweep_whose_estimators_run_on_different_heads_says_so(caplog):
    from ledsim.cli.checks import _warn_mixed_heads
    from ledsim.loop.sweep import SweepGrid

    def grid(*estimators, **kw):
        return SweepGrid(estimators=estimators, disturbances=["none"], distances=[30.0],
                         noise_scales=[1.0], seeds=1, base=RunSpec(link="luma", **kw))

    with caplog.at_level("WARNING", logger="ledsim"):
        _warn_mixed_heads(grid("ekf", "kkl-bank"))
        assert "ekf on the pan-tilt, kkl-bank on the yaw" in caplog.text
        caplog.clear()
        _warn_mixed_heads(grid("ekf", "kkl-bank", gimbal="yaw"))
        _warn_mixed_heads(grid("ekf", "kkl"))
        assert caplog.text == ""
