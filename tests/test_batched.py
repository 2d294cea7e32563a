"""The batched closed loop gives every seed the single run's numbers; its sensor is the
ray sensor; its estimators are the single estimators."""

from __future__ import annotations

import numpy as np
import pytest

from ledsim.loop.batched import BatchedClosedLoop, run_batch
from ledsim.loop.closed_loop import run_once
from ledsim.loop.config import RunConfig
from ledsim.loop.gate import BatchDropoutGate, DropoutGate
from ledsim.physics.batch import WorldBatch
from ledsim.physics.batch_sensor import BatchSensor
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld, WorldError

TOL = 1e-9


def _assert_same(cfg: RunConfig, seeds=(0, 1), threads: int = 1) -> None:
    batch = run_batch(cfg, seeds, keep_trace=True, threads=threads)
    for seed, b in zip(seeds, batch, strict=True):
        s = run_once(cfg, seed, keep_trace=True)
        for name in ("x", "xhat", "power", "power_clean", "torque"):
            np.testing.assert_allclose(getattr(b.trace, name), getattr(s.trace, name),
                                       rtol=0, atol=TOL, err_msg=f"{name}, seed {seed}")
        np.testing.assert_array_equal(b.trace.occluded, s.trace.occluded)
        np.testing.assert_array_equal(b.trace.lost, s.trace.lost)
        assert b.metrics.availability == pytest.approx(s.metrics.availability, abs=TOL)


@pytest.mark.parametrize("kw", [
    dict(estimator="kkl", supervision=False),
    dict(estimator="ekf", supervision=False),
    dict(estimator="ukf", supervision=False),
    dict(estimator="pf", supervision=False, particles=200),
    dict(estimator="oracle"),
], ids=["kkl", "ekf", "ukf", "pf", "oracle"])
def test_vectorised_estimators_match_single_runs(kw):
    _assert_same(RunConfig(seconds=2.5, **kw))


@pytest.mark.parametrize("kw", [
    dict(estimator="kkl", supervision=False,
         disturbances=("occlusion:start=1.2,duration=0.4",)),
    dict(estimator="ekf", disturbances=("kick:start=1.5,rate=8",)),
    dict(estimator="kkl", disturbances=("vibration:frequency=3,torque=0.5",
                                        "current:speed=0.05,gust=0.02")),
], ids=["occlusion-kkl", "kick-supervised-ekf", "vibration-current-bank"])
def test_disturbed_and_supervised_runs_match_single_runs(kw):
    _assert_same(RunConfig(seconds=2.5, **kw), threads=2)


def test_a_seed_gives_the_same_numbers_in_any_batch():
    cfg = RunConfig(estimator="kkl", supervision=False, seconds=1.5)
    alone = run_batch(cfg, [2], keep_trace=True)[0]
    among = run_batch(cfg, [0, 1, 2, 3], keep_trace=True)[2]
    np.testing.assert_allclose(among.trace.xhat, alone.trace.xhat, rtol=0, atol=TOL)


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


def test_batch_gate_is_the_gate():
    from ledsim.config import LinkConstants

    c = LinkConstants()
    rng = np.random.default_rng(1)
    ys = np.abs(rng.normal(0.0, 1.0, (300, 3, 2))) * np.where(rng.random((300, 3, 1)) < 0.2,
                                                             0.01, 1.0)
    batch = BatchDropoutGate(c, floor=0.3, max_hold=0.05)
    singles = [DropoutGate(c, floor=0.3, max_hold=0.05) for _ in range(3)]
    for y in ys:
        out = batch(y)
        for k, g in enumerate(singles):
            np.testing.assert_array_equal(out[k], g(y[k]))


def test_unstable_physics_in_a_batch_is_a_world_error():
    cfg = RunConfig(estimator="oracle", integrator="euler", seconds=3.0,
                    disturbances=("kick:start=2,rate=50,hull=1",))
    with pytest.raises(WorldError, match="unstable after t = 2.0"):
        run_batch(cfg, [0, 1])


def test_worlds_share_a_model_unless_a_disturbance_changes_it():
    shared = BatchedClosedLoop(RunConfig(estimator="oracle", seconds=0.1), [0, 1])
    own = BatchedClosedLoop(RunConfig(estimator="oracle", seconds=0.1,
                                      disturbances=("current:speed=0.1",)), [0, 1])
    a, b = shared.batch.worlds, own.batch.worlds
    assert a[0].model is a[1].model
    assert b[0].model is not b[1].model
    assert parse_disturbance("current").changes_model
    shared.batch.close()
    own.batch.close()


def test_run_many_batches_a_workers_seeds_and_keeps_their_numbers():
    from ledsim.loop.report import BATCH_MIN, run_many

    cfg = RunConfig(estimator="ekf", supervision=False, seconds=1.0, seeds=BATCH_MIN,
                    workers=1)
    summary, trace = run_many(cfg, progress=False)
    singles = [run_once(cfg, s, keep_trace=s == 0) for s in range(BATCH_MIN)]
    np.testing.assert_allclose(trace.xhat, singles[0].trace.xhat, rtol=0, atol=TOL)
    assert summary.mean_power.mean == pytest.approx(
        np.mean([o.metrics.mean_power for o in singles]), abs=TOL)
