"""Records that replay: a saved trace holds what its estimator was given, and a fresh
estimator (or an ONNX export of it) given the same gives the same estimates."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.loop.closed_loop import run_once
from ledsim.loop.config import RunConfig
from ledsim.loop.replay import ReplayError, replay
from ledsim.resources import require_shipped_checkpoint

OCCLUSION = ("occlusion:start=2,duration=1",)


def _save(tmp_path, name="t", **kw):
    cfg = RunConfig(seconds=4.0, disturbances=OCCLUSION, particles=300, **kw)
    series = run_once(cfg, 1, keep_trace=True).trace.series()
    path = tmp_path / f"{name}.npz"
    np.savez_compressed(path, **series)
    return path, series


@pytest.mark.parametrize("estimator", ["kkl", "ekf", "pf", "kkl-bank"])
def test_a_fresh_estimator_given_the_trace_gives_the_runs_estimates(tmp_path, estimator):
    """Over an occlusion with the IMU on (the gate withholds samples, the supervisor
    carries the estimate on the encoder and re-seeds it, the hull's motion is an
    input), bit for bit."""
    path, series = _save(tmp_path, estimator=estimator)
    steps = len(series["t"])
    occluded = (series["t"] > 2.2) & (series["t"] < 2.8)
    assert series["withheld_p1"][occluded].all() and not series["withheld_p1"][:150].any()
    assert np.abs(series["u_hull"]).max() > 0  # the hull's part of the input
    assert len(series["u"]) == len(series["gain"]) == len(series["reseeded"]) == steps
    result = replay(path)
    assert result.estimates >= steps and result.max_abs_difference <= 1e-9


@pytest.mark.parametrize("estimator", ["ekf", "pf"])
def test_a_reseed_with_its_covariance_replays(tmp_path, estimator):
    """The minimum-time acquisition restarts a filter from the fix with the fix's own
    covariance: the record keeps it, and the replay gives it back."""
    path, series = _save(tmp_path, estimator=estimator, acquisition="minimum-time")
    kinds = series["call_kind"]
    resets = series["call_nargs"][kinds == 1]
    assert (resets == 2 + 4).any()  # x0 and its 2x2 covariance
    assert replay(path).max_abs_difference == 0.0


def test_the_onnx_export_replays_to_1e_6(tmp_path):
    pytest.importorskip("onnxruntime")
    ckpt = require_shipped_checkpoint(0.085, "mujoco")  # the fixed-gain MuJoCo KKL
    path, _ = _save(tmp_path, estimator="kkl", checkpoint=str(ckpt))
    onnx = tmp_path / "kkl.onnx"
    r = run_cli("export", "--checkpoint", str(ckpt), "--out", str(onnx), "-q")
    assert r.returncode == 0, r.stderr
    r = run_cli("replay", str(path), "--onnx", str(onnx), "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["against"] == "onnx" and res["estimates"] == 400
    assert res["max_abs_difference"] <= 1e-6
    assert replay(path).max_abs_difference <= 1e-9  # and the numpy observer, exactly


def test_replay_refuses_what_it_cannot_replay_in_one_line(tmp_path):
    path, _ = _save(tmp_path, estimator="kkl")  # the gain-scheduled KKL
    r = run_cli("replay", str(path), "--onnx", str(tmp_path / "x.onnx"))
    assert_user_error(r, "not one: replay it without --onnx")
    oracle, _ = _save(tmp_path, "oracle", estimator="oracle")
    assert_user_error(run_cli("replay", str(oracle)), "nothing to replay")
    plain = tmp_path / "plain.npz"
    np.savez(plain, t=np.zeros(3), phi=np.zeros(3))  # a trace saved before records
    assert_user_error(run_cli("replay", str(plain)), "--save-trace")
    bad = tmp_path / "bad.npz"
    bad.write_text("not a trace")
    assert_user_error(run_cli("replay", str(bad)), "not a .npz trace")
    assert_user_error(run_cli("replay", str(tmp_path / "none.npz")), "does not exist")
    with pytest.raises(ReplayError, match="does not exist"):
        replay(tmp_path / "none.npz")


def test_run_save_trace_keeps_the_record_and_replay_reads_it(tmp_path):
    r = run_cli("run", "--estimator", "ekf", "--disturbance", OCCLUSION[0], "--seconds",
                "3", "--seeds", "1", "--save-trace", "--no-plot", "-q", "--out",
                str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    trace = tmp_path / "o" / "trace_seed0.npz"
    with np.load(trace) as z:
        assert {"t", "phi", "phi_hat", "p1", "lost", "withheld_p1", "u", "u_hull",
                "reseeded", "gain", "config", "call_kind"} <= set(z.files)
    r = run_cli("replay", str(trace))
    assert r.returncode == 0, r.stderr
    assert "largest difference 0" in r.stdout
