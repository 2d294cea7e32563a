"""Hostile numbers and specs are refused at the edge: one line, exit 2, nothing written."""

import pytest
from conftest import assert_user_error, run_cli

from ledsim.physics.disturbances import DisturbanceError, parse_disturbance


@pytest.mark.parametrize("args,needle", [
    (["simulate", "--seconds", "inf"], "--seconds"),
    (["simulate", "--torque-frequency", "inf"], "--torque-frequency"),
    (["simulate", "--gimbal-angle", "nan"], "--gimbal-angle"),
    (["simulate", "--led-yaw", "nan"], "--led-yaw"),
    (["simulate", "--distance", "1e308"], "--distance"),
    (["simulate", "--seed", "-1"], "--seed"),
    (["simulate", "--disturbance", "current:speed=1e308"], "current.speed"),
    (["simulate", "--disturbance", "vibration:torque=1e308,force=1e308"], "vibration.torque"),
    (["simulate", "--disturbance", "occlusion:start=30"], "after the end"),
    (["run", "--noise-scale", "inf"], "--noise-scale"),
    (["run", "--estimator", "pf", "--particles", "0"], "--particles"),
    (["run", "--estimator", "pf", "--particles", "10000000000000"], "--particles"),
    (["run", "--seeds", "-1"], "--seeds"),
    (["run", "--workers", "0"], "--workers"),
    (["run", "--disturbance", "occlusion:start=11"], "after the end"),
    (["render", "--fps", "inf"], "--fps"),
    (["run", "--depth", "0.5"], "--depth"),
    (["run", "--depth", "nan"], "--depth"),
    (["sweep", "--transmitter-depth", "0"], "--transmitter-depth"),
    (["run", "--transmitter-depth", "100"], "--transmitter-depth"),
    (["run", "--link", "paper", "--disturbance", "flicker"], "physical link"),
    (["evaluate", "--scenario", "if1", "--distance", "inf"], "--distance"),
])
def test_hostile_numbers_are_refused_before_any_work(tmp_path, args, needle):
    out = tmp_path / ("v.mp4" if args[0] == "render" else "out")
    r = run_cli(*args, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists()


def test_train_checks_its_output_before_training(tmp_path):
    for out, needle in ((tmp_path, "is a folder"), (tmp_path / "no" / "x.pt", "does not exist"),
                        (tmp_path / "x.txt", ".pt")):
        r = run_cli("train", "--samples", "1000", "--out", str(out))
        assert_user_error(r, needle)
        assert "trained" not in r.stderr


@pytest.mark.parametrize("spec", ["vibration:frequency=0", "vibration:frequency=51",
                                  "current:gust=-1", "current:hold=0.5", "current:seed=-1",
                                  "transmitter:sway=10", "occlusion:duration=0",
                                  "occlusion:start=-1", "vibration:torque=nan"])
def test_disturbance_keys_have_physical_ranges(spec):
    with pytest.raises(DisturbanceError, match=spec.split(":")[1].split("=")[0]):
        parse_disturbance(spec)


class _Payload:
    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        import os

        return (os.system, (f"touch {self.marker}",))


@pytest.mark.parametrize("protocol", [2, 4])
def test_a_pickle_with_a_payload_is_refused_in_one_line(tmp_path, protocol):
    import pickle

    marker = tmp_path / "pwned"
    evil = tmp_path / "evil.pt"
    evil.write_bytes(pickle.dumps(_Payload(marker), protocol=protocol))
    r = run_cli("evaluate", "--scenario", "if1", "--seeds", "1", "--checkpoint", str(evil),
                "--out", str(tmp_path / "out"))
    assert_user_error(r, "evil.pt")
    assert not marker.exists() and not (tmp_path / "out").exists()
