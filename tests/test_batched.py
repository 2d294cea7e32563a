"""Runs stepped together give every seed exactly the numbers it gets alone, whatever
the batch, the threads or the workers; the vectorised sensor (training data) is the ray
sensor."""

from __future__ import annotations

import numpy as np
import pytest

from ledsim.loop.closed_loop import ClosedLoop, run_batch, run_once
from ledsim.loop.report import run_many
from ledsim.loop.run_config import RunConfig
from ledsim.physics.batch import WorldBatch
from ledsim.physics.batch_sensor import BatchSensor
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld, WorldError

FIELDS = ("x", "xhat", "power", "power_clean", "torque", "occluded", "lost", "acquiring")


def _assert_identical(a, b, what: str) -> None:
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a.trace, name), getattr(b.trace, name),
                                      err_msg=f"{name}, {what}")
    assert a.metrics.availability == b.metrics.availability


@pytest.mark.parametrize("kw", [
    dict(estimator="kkl", supervision=False),
    dict(estimator="pf", supervision=False, particles=200),
    dict(estimator="oracle"),
    dict(estimator="kkl", supervision=False,
         disturbances=("occlusion:start=1.2,duration=0.4",)),
    dict(estimator="ekf", disturbances=("kick:start=1.5,rate=8",)),
    dict(estimator="kkl", disturbances=("vibration:frequency=3,torque=0.5",
                                        "current:speed=0.05,gust=0.02")),
    dict(estimator="kkl", link="luma", gimbal="yaw", disturbances=("scintillation", "flicker")),
    dict(estimator="ekf", link="luma", gimbal="yaw", depth=3.0,
         disturbances=("waves:height=1.5,period=6,heading=1.5708",)),
    # the pan-tilt (a physical link's default): its first step reads the gyro
    dict(estimator="kkl", link="luma", disturbances=("scintillation", "flicker")),
    dict(estimator="ekf", link="luma", depth=3.0,
         disturbances=("waves:height=1.5,period=6,heading=1.5708",)),
], ids=["kkl", "pf", "oracle", "occlusion-kkl", "kick-supervised-ekf",
        "vibration-current-bank", "light-luma-kkl", "strip-waves-luma-ekf",
        "light-luma-pan-tilt-kkl", "strip-waves-luma-pan-tilt-ekf"])
def test_a_batch_gives_each_seed_its_single_run_exactly(kw):
    cfg = RunConfig(seconds=2.5, **kw)
    batch = run_batch(cfg, [0, 1, 2], keep_trace=True, threads=2)
    for seed, b in zip((0, 1, 2), batch, strict=True):
        _assert_identical(b, run_once(cfg, seed, keep_trace=True), f"seed {seed}")


@pytest.mark.parametrize("kw", [
    dict(disturbances=("current:speed=0.05,gust=0.02",)),
    dict(disturbances=("waves:height=0.3,period=4", "dvl_dropout:start=0.3,duration=0.2")),
], ids=["current", "waves-dvl-dropout"])
def test_a_seed_is_the_same_in_batches_of_1_3_and_64(kw):
    cfg = RunConfig(seconds=0.6, **kw)
    big = run_batch(cfg, range(64), keep_trace=True)
    three = run_batch(cfg, [0, 31, 63], keep_trace=True)
    for j, seed in enumerate((0, 31, 63)):
        one = run_once(cfg, seed, keep_trace=True)
        _assert_identical(big[seed], one, f"seed {seed} of 64")
        _assert_identical(three[j], one, f"seed {seed} of 3")


@pytest.mark.parametrize("supervision", [False, True], ids=["unsupervised", "supervised"])
def test_the_same_command_gives_the_same_numbers_for_any_workers(supervision):
    # The case that differed (availability 0.1007 with one worker, 0.1247 with three):
    # an unsupervised KKL thrown out of its box by sway and hard vibration.
    cfg = RunConfig(estimator="kkl", supervision=supervision, seeds=3, seconds=4.0,
                    disturbances=("transmitter:sway=0.02,frequency=0.7",
                                  "vibration:frequency=5,torque=1,force=4"))
    results = {}
    for workers in (1, 2, 3):
        summary, trace = run_many(RunConfig(**{**cfg.__dict__, "workers": workers}),
                                  progress=False)
        results[workers] = (summary.availability.mean, summary.rmse_steady_x1.mean,
                            trace.xhat)
    for workers in (2, 3):
        assert results[workers][:2] == results[1][:2], f"--workers {workers}"
        np.testing.assert_array_equal(results[workers][2], results[1][2])


def _batch_at(states, occluder=None):
    worlds, sensors = [], []
    for q, yaw in states:
        w = LinkWorld()
        w.reset(gimbal_angle=q)
        w.set_transmitter(w.transmitter_home, yaw=yaw)
        sensors.append(IrradianceSensor(w, noise=False))
        if occluder is not None:
            w.set_occluder(occluder(w))
        worlds.append(w)
    batch = WorldBatch(worlds, [[] for _ in worlds])
    return batch, BatchSensor(batch, sensors, steps=1), sensors


def test_batch_sensor_is_the_ray_sensor_and_casts_rays_only_near_an_occluder():
    rng = np.random.default_rng(4)
    states = [(q, y) for q, y in zip(rng.uniform(-0.4, 0.4, 12), rng.uniform(-0.3, 0.3, 12),
                                     strict=True)]
    # The plate at the link's middle, shifted so it covers none, part or all of the beam.
    shifts = iter(np.linspace(-0.04, 0.04, 12))

    def plate(w):
        w.forward_kinematics()
        mid = w.link_midpoint()
        return [mid[0], mid[1], mid[2] + next(shifts)]

    for occluder in (None, plate):
        batch, sensor, singles = _batch_at(states, occluder)
        r = sensor.read()
        for k, s in enumerate(singles):
            one = s.read(noise=False)
            np.testing.assert_allclose(r.power[k], one.power, rtol=1e-12, atol=1e-18)
            np.testing.assert_allclose(r.incidence_angle[k], one.incidence_angle, atol=1e-12)
            np.testing.assert_array_equal(r.visible_fraction[k], one.visible_fraction)
            np.testing.assert_allclose(r.phidot[k], one.phidot, atol=1e-12)
        if occluder is None:
            assert not r.rays.any(), "a clear line of sight cast rays"
        else:
            assert r.rays.any() and (r.visible_fraction < 1).any()
            assert (r.visible_fraction[r.rays] < 1).any()
        batch.close()


def test_unstable_physics_in_a_batch_is_a_world_error():
    cfg = RunConfig(estimator="oracle", integrator="euler", seconds=3.0,
                    disturbances=("kick:start=2,rate=50,hull=1",))
    with pytest.raises(WorldError, match="unstable after t = 2.0"):
        run_batch(cfg, [0, 1], threads=2)


def test_worlds_share_a_model_unless_a_disturbance_changes_it():
    shared = ClosedLoop(RunConfig(estimator="oracle", seconds=0.1), [0, 1])
    own = ClosedLoop(RunConfig(estimator="oracle", seconds=0.1,
                               disturbances=("current:speed=0.1",)), [0, 1])
    a, b = [r.world for r in shared.runs], [r.world for r in own.runs]
    assert a[0].model is a[1].model
    assert b[0].model is not b[1].model
    assert parse_disturbance("current").changes_model
