"""The vehicle: station keeping from its own navigation, the IMU's line-of-sight
feed-forward, waves, hull kicks, and the metrics that cannot mislead."""

import json
import math

import numpy as np
import pytest
from conftest import run_cli

from ledsim.constants import LinkConstants
from ledsim.errors import LedsimError
from ledsim.loop.closed_loop import run_batch, run_once
from ledsim.loop.report import summarize
from ledsim.loop.run_config import RunConfig
from ledsim.loop.run_metrics import run_metrics
from ledsim.loop.table import recovered
from ledsim.loop.validation import navigation_noise
from ledsim.physics.disturbances import DisturbanceError, parse_disturbance


def test_waves_give_the_orbital_velocity_of_linear_deep_water_waves():
    w = parse_disturbance("waves:height=1.5,period=6,depth=10")
    omega = 2 * math.pi / 6
    assert w.amplitude == pytest.approx(0.75 * omega * math.exp(-omega**2 / 9.81 * 10))
    assert parse_disturbance("waves:height=1.5,period=10").amplitude > w.amplitude  # longer
    for bad in ("waves:height=-1", "waves:period=0.5", "waves:depth=0", "waves:bogus=1"):
        with pytest.raises(DisturbanceError):
            parse_disturbance(bad)


def test_the_imu_keeps_the_link_in_a_cross_current_where_the_photodiodes_alone_lose_it():
    spec = ("current:speed=0.1,heading=1.5708,gust=0.05",)
    aided = run_batch(RunConfig(estimator="kkl", disturbances=spec), [0, 1], threads=2)
    alone = run_batch(RunConfig(estimator="kkl", disturbances=spec, imu=False), [0, 1],
                      threads=2)
    assert min(o.metrics.availability for o in aided) > 0.9
    # Without the IMU the minimum-time reacquisition wins back part of it (0.6-0.65,
    # lost 40% of the time); the warm-up's slow scan did not (0.0).
    assert max(o.metrics.availability for o in alone) < 0.75
    assert min(o.metrics.lost_share for o in alone) > 0.3
    slow = run_batch(RunConfig(estimator="kkl", disturbances=spec, imu=False,
                               acquisition="warm-up"), [0, 1], threads=2)
    assert max(o.metrics.availability for o in slow) < 0.3


def test_a_hull_kick_is_flagged_within_0_2_s_and_the_link_comes_back():
    out = run_once(RunConfig(estimator="kkl", disturbances=("kick:start=3,rate=3,hull=1",),
                             seconds=8), seed=0)
    m = out.metrics
    assert m.detection_delay is not None and m.detection_delay <= 0.2
    assert m.recovery_time is not None and m.recovery_time < 4.0


def test_drifting_with_the_water_is_hold_0_and_no_station_keeping():
    assert RunConfig(disturbances=("current:hold=0",)).station_keeps is False
    assert RunConfig(disturbances=("waves:hold=0",)).station_keeps is False
    assert RunConfig(station_keeping=False).station_keeps is False
    assert RunConfig(disturbances=("current",)).station_keeps is True


def test_bad_sensor_noise_is_refused_naming_it():
    assert navigation_noise(("dvl_noise=0.01",)).dvl_noise == 0.01
    for bad, word in (("dvl_noise=-1", "dvl_noise"), ("gyro_bias_instability=nan", "nan"),
                      ("nosuch=1", "nosuch"), ("fix_noise=x", "'x'")):
        with pytest.raises(LedsimError, match=word):
            RunConfig(imu_noise=(bad,)).validate()
    assert RunConfig(station_keeping_gains=("kd=100",)).world.keeping_gains().kd == 100.0
    for bad in ("kd=-1", "observer_time=0", "kp=inf", "stiff=1"):
        with pytest.raises(LedsimError, match="--station-keeping-gain"):
            RunConfig(station_keeping_gains=(bad,)).validate()


def test_availability_counts_only_a_geometry_that_allows_a_link():
    c = LinkConstants()
    n = 200
    x = np.zeros((n, 2))
    best = np.full(n, 1.0)
    best[100:] = 1e-4  # the hull turned the receiver away: next to nothing is possible
    p = np.c_[0.95 * best, 0.95 * best]  # 95% of the possible: "available" by ratio alone
    m = run_metrics(x, x, p, 0.5, c, power_max=best, noise_std=c.measurement_noise_std)
    assert m.geometry_share == pytest.approx(0.5)
    assert m.availability == pytest.approx(0.5)


def test_recovery_is_measured_on_availability_windows_relative_to_before_the_event():
    c = LinkConstants()
    Te, n = c.Te, 1000
    x = np.zeros((n, 2))
    best = np.ones(n)
    up = np.ones(n, dtype=bool)
    up[::2] = False  # a vibrating hull: available every other step, oracle or not
    up[300:400] = False  # the event, 3-4 s
    p = np.where(up, 0.95, 0.1)[:, None] * np.ones(2)
    m = run_metrics(x, x, p, 0.5, c, event_end=4.0, event_start=3.0, power_max=best,
                    noise_std=c.measurement_noise_std)
    assert m.recovery_time == pytest.approx(0.0, abs=2 * Te)  # back at once, as before


def test_tables_say_how_many_seeds_recovered():
    outs = run_batch(RunConfig(estimator="oracle", seconds=4, seeds=2,
                               disturbances=("occlusion:start=2,duration=0.3",)), [0, 1])
    s = summarize(RunConfig(estimator="oracle", seconds=4, seeds=2,
                            disturbances=("occlusion:start=2,duration=0.3",)), outs)
    assert recovered(s).endswith("(2/2)")
    from dataclasses import replace

    from ledsim.loop.report import Stat

    never = Stat(None, None, 0)
    assert recovered(replace(s, recovery_time=never)) == "- (0/2)"
    assert recovered(replace(s, recovery_time=never, disturbances=[])) == "-"


def test_cli_no_imu_and_a_scene_without_the_vehicles_sensors(tmp_path):
    import re

    from ledsim.files.resources import scene_path

    xml = re.sub(r"<sensor>.*?</sensor>", "", scene_path().read_text(), flags=re.S)
    scene = tmp_path / "bare.xml"
    scene.write_text(xml)
    r = run_cli("run", "--scene", str(scene), "--seeds", "1", "--seconds", "1", "--no-plot",
                "--out", str(tmp_path / "a"))
    assert r.returncode == 2 and "--no-imu" in r.stderr and "Traceback" not in r.stderr
    r = run_cli("run", "--scene", str(scene), "--no-imu", "--seeds", "1", "--seconds", "1",
                "--no-plot", "--out", str(tmp_path / "b"))
    assert r.returncode == 0, r.stderr
    assert "no vehicle sensors" in r.stderr
    res = json.loads((tmp_path / "b" / "results.json").read_text())
    assert res["imu"] is False and res["station_keeping"] is False  # no vehicle: it drifts
    r = run_cli("run", "--imu-noise", "dvl_noise=-1", "--seeds", "1", "--out",
                str(tmp_path / "c"))
    assert r.returncode == 2 and "dvl_noise" in r.stderr and "Traceback" not in r.stderr
