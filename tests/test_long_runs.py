"""Station keeping that lasts, per-window metrics, the env as ``ledsim run`` under every
disturbance kind, and the defects a user found by trying the CLI."""

from __future__ import annotations

import json
import re

import gymnasium as gym
import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.constants import LinkConstants
from ledsim.loop.closed_loop import run_once
from ledsim.loop.run_config import RunConfig
from ledsim.loop.windows import window_metrics
from ledsim.physics.disturbances import DisturbanceError, parse_disturbance


def test_a_hull_in_still_water_stays_on_station_and_the_link_with_it():
    """Two minutes of still water: the oracle's link and FEC share hold in the second
    minute, the hull stays within the fixes' accuracy (it walked 9.5 cm in 30 s on the
    gyro-only attitude), and the navigation knows where it is."""
    out = run_once(RunConfig(estimator="oracle", seconds=120.0), seed=0, window=60.0)
    m = out.metrics
    assert m.hull_error_rms < 0.03 and m.navigation_error_rms < 0.02
    second = out.windows[1]
    assert second.availability >= 0.95 and second.fec_share >= 0.95
    assert out.station_keeping is True


def test_a_still_hull_does_not_shake_the_unsupervised_kkl():
    """Station keeping acts only on what stands out of its sensors' noise, so a hull in
    still water stays still and the KKL alone keeps the link (0.48 when the hull
    followed the navigation's noise)."""
    out = run_once(RunConfig(estimator="kkl", supervision=False), seed=0)
    assert out.metrics.availability > 0.8
    assert out.metrics.hull_error_rms < 0.005


def test_window_metrics_split_a_run_and_measure_each_part():
    c = LinkConstants()
    n = 600  # 6 s of 10 ms
    best = np.ones(n)
    p1 = np.where(np.arange(n) < 300, 0.95, 0.5)  # available for the first 3 s only
    hull = np.zeros((n, 3))
    hull[300:, 0] = 0.02  # 2 cm off station in the second half
    nav = hull.copy()
    nav[:, 1] = 0.01  # the navigation 1 cm off throughout
    w = window_metrics(p1, best, c.measurement_noise_std, c.Te, 3.0, hull, np.zeros(3), nav)
    assert [(x.start, x.end) for x in w] == [(0.0, 3.0), (3.0, 6.0)]
    assert [x.availability for x in w] == [1.0, 0.0]
    assert w[0].hull_error_rms == pytest.approx(0.0)
    assert w[1].hull_error_rms == pytest.approx(0.02)
    assert w[1].navigation_error_rms == pytest.approx(0.01)
    assert len(window_metrics(p1, best, 0.03, c.Te, 100.0)) == 1  # a short run: one
    with pytest.raises(ValueError, match="window"):
        window_metrics(p1, best, 0.03, c.Te, 0.0)


def test_run_reports_windows_and_the_vehicles_errors(tmp_path):
    r = run_cli("run", "--estimator", "oracle", "--seeds", "1", "--seconds", "4",
                "--window", "2", "--no-plot", "-q", "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    assert [(w["start"], w["end"]) for w in res["windows"]] == [(0.0, 2.0), (2.0, 4.0)]
    assert 0 <= res["windows"][1]["availability"]["mean"] <= 1
    assert 0 < res["hull_error_rms"]["mean"] < 0.03
    assert 0 < res["navigation_error_rms"]["mean"] < 0.03


KINDS = ["vibration:frequency=3,torque=0.25,force=1", "current:speed=0.2",
         "waves:height=1,period=6", "transmitter:sway=0.005,yaw=0.1",
         "occlusion:start=2,duration=1", "kick:start=2,rate=12",
         "kick:start=2,rate=3,hull=1", "dvl_dropout:start=1,duration=2",
         "occlusion:start=2,duration=1+vibration:frequency=3,torque=0.25,force=1"]


@pytest.mark.parametrize("spec", KINDS)
def test_the_shipped_policy_follows_ledsim_run_under_every_disturbance(spec):
    """Seed 1 of ``ledsim run`` and the env driven by the shipped policy stay equal to
    1e-9 under every disturbance kind, occlusions included."""
    import ledsim.envs  # noqa: F401 (registers the env)
    from ledsim.envs import ShippedAlignmentPolicy

    dists = tuple(re.split(r"\+(?=[a-z])", spec))
    seconds = 5.0
    trace = run_once(RunConfig(estimator="kkl", disturbances=dists, seconds=seconds),
                     seed=1, keep_trace=True).trace.series()
    env = gym.make("ledsim/LinkAlign-v0", scenario="align", disturbances=list(dists))
    policy = ShippedAlignmentPolicy(env.unwrapped)
    obs, info = env.reset(seed=1)
    phi = [info["phi"]]
    for _ in range(len(trace["t"]) - 1):
        obs, _, _, _, info = env.step(policy(obs))
        phi.append(info["phi"])
    env.close()
    np.testing.assert_allclose(phi, trace["phi"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("args,needle", [
    (["--seconds", "0.004"], "--seconds 0.004 is not allowed"),
    (["--disturbance", "current:speed=0.2,speed=0.3"], "current.speed is given twice"),
    (["--imu-noise", "fix_noise=0.1,fix_noise=0.2"], "fix_noise is given twice"),
    (["--scene", "/dev/null"], "is not a regular file"),
    (["--window", "0"], "--window"),
    (["--imu-noise", "fix_latency=9"], "fix_latency"),
])
def test_cli_defects_are_one_line_refusals(tmp_path, args, needle):
    out = tmp_path / "o"
    r = run_cli("run", "--seeds", "1", "--no-plot", *args, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists()


@pytest.mark.parametrize("args,needle", [
    (["--seconds", "10", "--window", "100"], "--window 100 is not allowed: it is longer "
     "than the 10 s run (--seconds)"),
    (["--window", "10.5"], "the align scenario's length"),
])
def test_a_window_longer_than_the_run_is_refused(tmp_path, args, needle):
    out = tmp_path / "o"
    r = run_cli("run", "--seeds", "1", "--no-plot", *args, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists()


def test_a_window_as_long_as_the_run_is_allowed():
    RunConfig(seconds=10.0, window=10.0).validate()
    RunConfig(window=10.0).validate()  # the align scenario's 10 s


def test_a_repeated_key_is_refused_in_the_library_too():
    with pytest.raises(DisturbanceError, match="twice"):
        parse_disturbance("kick:rate=2,rate=3")


def test_an_imu_less_scene_names_only_what_it_lacks_and_records_what_ran(tmp_path):
    import mujoco

    from ledsim.files.resources import scene_path

    spec = mujoco.MjSpec.from_file(str(scene_path()))
    for s in list(spec.sensors):
        if s.name in ("imu_gyro", "imu_accel"):
            spec.delete(s)
    scene = tmp_path / "no_imu.xml"
    scene.write_text(spec.to_xml())
    r = run_cli("run", "--scene", str(scene), "--seeds", "1", "--seconds", "1",
                "--no-plot", "--out", str(tmp_path / "a"))
    assert_user_error(r, "imu_gyro, imu_accel: run it with --no-imu")
    assert "dvl" not in r.stderr and "encoder" not in r.stderr
    r = run_cli("run", "--scene", str(scene), "--no-imu", "--seeds", "1", "--seconds", "1",
                "--no-plot", "-q", "--out", str(tmp_path / "b"))
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "b" / "results.json").read_text())
    assert res["imu"] is False and res["station_keeping"] is False
    assert res["hull_error_rms"]["mean"] is None
