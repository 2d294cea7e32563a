"""The gain-scheduled KKL: maps over a range of gains, a schedule, its checkpoint."""

from dataclasses import replace

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.constants import LinkConstants
from ledsim.paper.model import LEDLinkModel
from observer.exceptions import ObserverError
from observer.kkl import checkpoint as ckpt
from observer.kkl.gainmaps import GainTableMap
from observer.kkl.scheduled import GainSchedule, ScheduledDesign, ScheduledKKL
from observer.kkl.scheduled_training import ScheduledTrainingConfig, train_scheduled_kkl
from observer.kkl.training import generate_transitions


@pytest.fixture(scope="module")
def scheduled(system):
    """A small gain-scheduled KKL of the paper's model, trained in a few seconds."""
    data = generate_transitions(system, 30_000, 0.0, np.random.default_rng(0))
    cfg = ScheduledTrainingConfig(hidden=300, decoder_hidden=300, gains=6, noise_levels=2,
                                  decoder_samples=15_000)
    obs, report = train_scheduled_kkl(system, ScheduledDesign(noise_range=(1.0, 4.0)), data,
                                      cfg, progress=False)
    return obs, report


def _run(est, system, x0, steps, seed=0):
    """Simulate the plant from x0 (no input) and return the estimation errors."""
    rng = np.random.default_rng(seed)
    x, errs = np.asarray(x0, float), []
    for _ in range(steps):
        y = system.h(x) + rng.standard_normal(2) * system.measurement_noise_std
        errs.append(est.update(y) - x)
        est.predict(0.0)
        x = system.f(x, 0.0) + rng.standard_normal(2) * system.process_noise_std
    return np.array(errs)


def test_the_encoder_is_learned_at_every_grid_gain(scheduled):
    _, report = scheduled
    assert report["residual_rel_worst"] < 0.05
    assert np.asarray(report["recon_rmse"]).shape == (6, 2, 2)


def test_the_schedule_starts_fast_and_settles_to_a_floor_set_by_the_noise(scheduled, system):
    obs, _ = scheduled
    shipped = obs.schedule
    # This tiny test network's two decoders differ by more than the shipped pair's.
    obs.schedule = replace(shipped, disagree=1.0)
    obs.set_noise(1.0)
    obs.reset([0.01, 0.0])
    assert obs.w == pytest.approx(2.0)
    _run(obs, system, [0.01, 0.0], 400)  # near the operating point: it slows and locks
    assert obs.w == pytest.approx(obs.schedule.floor(1.0), rel=0.06)
    assert obs.locked == 1.0
    # A locked decoder that parts from the wide one (powers the model does not explain)
    # is dropped at once, and the estimate is the wide decoder's.
    locked = obs.decoder_locked
    obs.decoder_locked = lambda z, w, s: locked(z, w, s) + np.array([0.0, 0.6])
    x = obs.update(system.h(np.array([0.01, 0.0])))
    assert obs.locked == 0.0
    np.testing.assert_allclose(x, obs.decoder_T_star(obs.z, obs.w, obs.noise))
    obs.decoder_locked, obs.schedule = locked, shipped
    obs.set_noise(4.0)
    obs.reset([0.01, 0.0])
    assert obs.w < 2.0  # a noisy link starts slower
    _run(obs, system, [0.01, 0.0], 400)
    assert obs.w < obs.schedule.floor(1.0)  # and averages longer


def test_far_from_the_operating_point_it_does_not_slow_down(scheduled, system):
    obs, _ = scheduled
    obs.set_noise(1.0)
    obs.reset([0.3, 0.0])
    _run(obs, system, [0.3, 0.0], 300)
    assert obs.w >= obs.schedule.recover_gain(1.0)
    assert obs.locked == 0.0


def test_it_converges_from_a_wrong_guess_and_is_precise_once_settled(scheduled, system):
    obs, _ = scheduled
    obs.set_noise(1.0)
    for seed, x0 in enumerate(([0.3, 0.0], [-0.25, 0.02], [0.1, -0.02])):
        obs.reset()  # guess: the domain centre
        err = _run(obs, system, x0, 800, seed)
        assert np.sqrt((err[400:, 0] ** 2).mean()) < 0.03, x0


def test_a_gain_change_keeps_the_estimate(scheduled, system):
    obs, _ = scheduled
    obs.reset([0.1, 0.0])
    _run(obs, system, [0.1, 0.0], 50)
    before = obs.decode(obs.z)
    obs.set_gain(obs.w * 0.6)
    after = obs.decode(obs.z)
    assert np.abs(after - before).max() < 0.02


def test_round_trip_and_refusals(scheduled, system, tmp_path):
    obs, _ = scheduled
    path = ckpt.save(obs, tmp_path / "s.pt")
    back = ckpt.load(path, system)
    assert isinstance(back, ScheduledKKL)
    assert back.design == obs.design and back.schedule == obs.schedule
    for est in (obs, back):
        est.set_noise(1.0)
        est.reset()
    np.testing.assert_allclose(_run(back, system, [0.2, 0.0], 200),
                               _run(obs, system, [0.2, 0.0], 200), atol=1e-12)
    with pytest.raises(ckpt.CheckpointError, match="distance"):
        ckpt.load(path, LEDLinkModel(LinkConstants(distance=0.2)))
    from observer.kkl import scheduled_checkpoint as sc

    bad = sc.arrays(obs)
    bad["decoder_T_star.coef"] = bad["decoder_T_star.coef"].copy()
    bad["decoder_T_star.coef"][0, 0, 0, 0] = np.nan
    import json

    from safetensors.numpy import save_file

    save_file({k: np.ascontiguousarray(v) for k, v in bad.items()},
              tmp_path / "nan.safetensors",
              metadata={"format": sc.FORMAT, "metadata_json": json.dumps(sc.metadata(obs))})
    with pytest.raises(ckpt.CheckpointError, match="corrupt"):
        ckpt.load(tmp_path / "nan.safetensors", system)


def test_table_maps_interpolate_between_grid_gains():
    rng = np.random.default_rng(1)
    coef = rng.standard_normal((3, 1, 2, 5))
    m = GainTableMap(rng.standard_normal((4, 2)), rng.standard_normal(4), coef,
                     np.log([0.5, 1.0, 2.0]), [0.0])
    v = rng.standard_normal((7, 2))
    lo, hi, mid = m(v, 0.5), m(v, 1.0), m(v, np.sqrt(0.5))
    np.testing.assert_allclose(mid, 0.5 * (lo + hi))
    np.testing.assert_allclose(m(v, 0.1), lo)  # clipped to the grid
    assert m.consistent()
    assert not GainTableMap(np.ones((4, 2)), np.ones(3), coef, np.log([0.5, 1, 2]),
                            [0.0]).consistent()


@pytest.mark.parametrize("kwargs", [dict(w_range=(0.0, 1.0)), dict(w_range=(2.0, 1.0)),
                                    dict(slowest=6.0, fastest=10.0), dict(n_rates=1),
                                    dict(lock_box=0.0)])
def test_bad_designs_are_refused(kwargs):
    with pytest.raises(ObserverError):
        ScheduledDesign(**kwargs)


@pytest.mark.parametrize("kwargs", [dict(start=0.0), dict(step_ratio=0.9),
                                    dict(noise_power=-1.0), dict(lock_ramp=0.0)])
def test_bad_schedules_are_refused(kwargs):
    with pytest.raises(ObserverError):
        GainSchedule(**kwargs)


def test_kkl_scheduled_runs_in_the_loop(tmp_path):
    r = run_cli("run", "--estimator", "kkl-scheduled", "--seconds", "5", "--seeds", "1",
                "--workers", "1", "--no-plot", "-q", "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    import json

    res = json.loads((tmp_path / "o" / "results.json").read_text())
    assert res["estimator"] == "kkl-scheduled"
    assert res["availability"]["mean"] > 0.6


def test_kkl_scheduled_without_supervision_elsewhere_is_refused(tmp_path):
    r = run_cli("run", "--estimator", "kkl-scheduled", "--no-supervision", "--distance", "0.2",
                "--out", str(tmp_path / "o"))
    assert_user_error(r, "kkl-scheduled")


def test_the_shipped_checkpoint_is_what_train_design_scheduled_makes():
    from dataclasses import asdict

    from ledsim.files.resources import shipped_checkpoint

    meta = ckpt.metadata(shipped_checkpoint(0.085, "mujoco", design="scheduled"))
    assert asdict(GainSchedule(**meta["schedule"])) == asdict(GainSchedule())
    assert ScheduledDesign.from_dict(meta["scheduled_design"]) == ScheduledDesign()


def test_while_the_motor_works_against_a_load_it_does_not_slow_down(scheduled, system):
    """GainSchedule.driven: a plant driven hard (mean |u| above the level) keeps the
    filters at driven_gain x recover; once quiet, the schedule settles as before. Off
    (None, the paper's schedule) a driven plant slows down like a quiet one."""
    obs, _ = scheduled
    shipped = obs.schedule
    obs.set_noise(1.0)

    def settle(u, steps=400):
        obs.reset([0.01, 0.0])
        x = np.array([0.01, 0.0])
        for _ in range(steps):
            obs.update(system.h(x))
            obs.predict(u)
        return obs.w

    try:
        obs.schedule = replace(shipped, disagree=1.0, driven=0.3, driven_gain=2.0)
        target = obs.clip(2.0 * obs.schedule.recover_gain(1.0))
        assert settle(0.5) == pytest.approx(target, rel=0.06)
        assert settle(0.0) == pytest.approx(obs.schedule.floor(1.0), rel=0.06)
        obs.schedule = replace(shipped, disagree=1.0)
        assert settle(0.5) < 0.7 * target
    finally:
        obs.schedule = shipped
