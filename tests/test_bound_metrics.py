"""Every table against the posterior Cramér-Rao bound, the pointing loss in which the
estimator decides, and the KKL saying when it leaves its training box."""

import json
import math

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.cli import main
from ledsim.loop.closed_loop import run_once
from ledsim.loop.report import run_seeds
from ledsim.loop.run_config import RunConfig
from ledsim.paper.evaluate import EvaluationConfig, evaluate
from ledsim.paper.pcrb_tables import pointing_loss
from observer.metrics import pointing_loss_db


def test_pointing_loss_weighs_power_not_decibels():
    assert pointing_loss_db([1.0, 1.0], [1.0, 1.0]) == 0.0
    assert pointing_loss_db([1.0, 1.0], [0.5, 0.5]) == pytest.approx(10 * math.log10(2))
    # a step with nothing received costs its power, not an infinite number of dB
    assert pointing_loss_db([1.0, 1.0], [1.0, 0.0]) == pytest.approx(10 * math.log10(2))
    assert pointing_loss_db([1.0], [0.0]) == math.inf
    assert math.isnan(pointing_loss_db([1.0, 1.0], [1.0, 1.0], np.array([False, False])))


def test_a_receiver_pointed_by_a_worse_estimate_loses_more(system):
    x = np.zeros((100, 2))
    good, bad = x.copy(), x.copy()
    good[:, 0], bad[:, 0] = 0.01, 0.1
    assert 0 < pointing_loss(system, x, good) < pointing_loss(system, x, bad)
    assert pointing_loss(system, x, x) == pytest.approx(0.0, abs=1e-12)


def test_the_tables_give_each_estimator_against_the_bound():
    """On the open-loop row the particle filter (5,000 particles) sits on the bound,
    within its Monte-Carlo error, and no estimator beats it by more than that."""
    cfg = EvaluationConfig(scenario="open-loop", seeds=4, starts=0, particles=5000,
                           workers=2, estimators=("kkl", "ekf", "pf"))
    res = evaluate(cfg, progress=False)
    for name, e in res.estimators.items():
        assert e.pcrb_steady_x1 > 0 and e.pcrb_steady_x2 > 0
        assert e.pointing_loss_db >= 0
        for k in ("x1", "x2"):
            ratio, err = e.rmse_over_pcrb[k], e.rmse_over_pcrb_err[k]
            assert ratio > 1 - 3 * err, (name, k, ratio, err)
    pf = res.estimators["pf"]
    assert abs(pf.rmse_over_pcrb["x2"] - 1) < 0.1 + 3 * pf.rmse_over_pcrb_err["x2"]


def test_evaluate_runs_one_estimator_by_name_and_refuses_an_unknown_one(tmp_path):
    out = tmp_path / "ev"
    code = main(["evaluate", "--scenario", "open-loop", "--seeds", "2", "--starts", "0",
                 "--estimator", "ekf", "--workers", "1", "-q", "--out", str(out)])
    assert code == 0
    res = json.loads((out / "results.json").read_text())
    assert list(res["estimators"]) == ["ekf"]
    e = res["estimators"]["ekf"]
    assert {"pcrb_steady_x1", "pcrb_steady_x2", "pointing_loss_db"} <= set(e)
    assert "x1/PCRB" in (out / "table.md").read_text()
    r = run_cli("evaluate", "--scenario", "open-loop", "--estimator", "oracle",
                "--out", str(tmp_path / "o"))
    assert_user_error(r, "oracle")
    r = run_cli("evaluate", "--scenario", "if1", "--distance", "0.15", "--estimator",
                "kkl-scheduled", "--out", str(tmp_path / "s"))
    assert_user_error(r, "--design scheduled")  # none shipped there: how to train one
    assert not (tmp_path / "s").exists()


def test_a_loop_summary_gives_the_bound_and_the_pointing_loss():
    summary, outs = run_seeds(RunConfig(estimator="ekf", seeds=2, seconds=4.0, workers=1),
                              progress=False)
    assert 0 < summary.pcrb_steady_x1 < 0.05 and 0 < summary.pcrb_steady_x2
    assert summary.rmse_over_pcrb_x1 > 0 and summary.rmse_over_pcrb_err_x1 >= 0
    assert summary.pointing_loss_db.n == 2 and summary.pointing_loss_db.mean >= 0
    oracle, _ = run_seeds(RunConfig(estimator="oracle", seeds=1, seconds=2.0, workers=1),
                          progress=False)
    assert oracle.pcrb_steady_x1 > 0 and oracle.rmse_over_pcrb_x1 is None


def test_an_occlusion_withholds_information_from_the_loops_bound():
    from observer.pcrb import posterior_crb

    out = run_once(RunConfig(estimator="ekf", seconds=4.0,
                             disturbances=("occlusion:start=2,duration=1",)), 0)
    phi_bound = posterior_crb(*_terms(out))[:, 0, 0]
    a, b = int(2.2 / 0.01), int(2.8 / 0.01)  # surely blind: the bound only grows
    assert np.all(np.diff(phi_bound[a:b]) > 0)
    assert phi_bound[b] > 1.3 * phi_bound[a - 50]
    assert phi_bound[-1] < phi_bound[b]  # the light is back: it falls again


def _terms(out):
    from observer.pcrb import BoundTerms

    return BoundTerms.from_arrays(out.bound), out.bound["prior"]


def test_the_kkl_says_when_its_state_or_its_input_leaves_the_training_box(
        system, tiny_observer):
    kkl = tiny_observer
    y_inside = system.h(np.array([0.1, 0.0]))
    kkl.reset(np.array([0.1, 0.0]))
    kkl.update(y_inside)
    assert not kkl.outside_domain
    kkl.predict(0.0)
    assert not kkl.outside_domain
    kkl.predict(1e4)  # an input that drives f(x_hat, u) far past the box's rate
    assert kkl.outside_domain
    kkl.reset(np.array([0.1, 0.0]))
    kkl.update(y_inside)
    assert not kkl.outside_domain
    kkl.z = kkl.encode(np.array([0.1, 0.0])) * 40  # a state far outside the box
    kkl.update(y_inside)
    assert kkl.outside_domain
    assert not kkl.in_domain(np.array([0.6, 0.0])) and kkl.in_domain(np.array([0.4, -0.4]))


def test_the_supervisor_reads_the_flag_into_the_run():
    out = run_once(RunConfig(estimator="kkl", seconds=3.0), 0)
    share = out.metrics.outside_domain_share
    assert 0 <= share < 0.2  # the minimum-time slew's rate leaves the box for a moment
    ekf = run_once(RunConfig(estimator="ekf", seconds=2.0), 0)
    assert ekf.metrics.outside_domain_share == 0.0  # a filter has no box to leave
