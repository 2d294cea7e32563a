"""scripts/rl_baseline.py trains PPO and RecurrentPPO for a few thousand steps and
writes the table's keys; bad input is one line and exit 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "rl_baseline.py"


def _run(*args, cwd):
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True,
                          text=True, timeout=900, cwd=cwd)


def test_a_short_baseline_writes_every_policys_figures(tmp_path):
    pytest.importorskip("sb3_contrib")
    r = _run("--steps", "4096", "--seeds", "1", "--out", str(tmp_path / "rl"), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "rl" / "results.json").read_text())
    for name in ("ppo", "recurrent_ppo", "shipped_kkl", "oracle", "shipped_kkl_warm_up",
                 "shipped_kkl_minimum_time", "oracle_warm_up", "oracle_minimum_time"):
        assert {"availability", "availability_steady", "mean_return", "train_seconds",
                "env_steps", "starts"} <= set(res[name]), name
        assert 0.0 <= res[name]["availability"] <= 1.0
        assert 0.0 <= res[name]["mean_return"] <= 1000.0
        assert set(res[name]["starts"]) == {"0.3", "1.0", "-0.45"}
        assert all(len(v) == 1 for v in res[name]["starts"].values())
    assert res["ppo"]["env_steps"] == 4096 and res["ppo"]["train_seconds"] > 0
    assert res["shipped_kkl"]["availability"] > 0.8  # ledsim run's stack holds the link
    assert res["shipped_kkl_minimum_time"]["starts"]["1.0"][0] > 0.9  # finds the beam
    assert (tmp_path / "rl" / "learning_curve.png").stat().st_size > 1000
    for name in ("ppo", "recurrent_ppo"):  # the trained policies, kept
        assert (tmp_path / "rl" / f"{name}.zip").stat().st_size > 1000


@pytest.mark.parametrize("args,needle", [
    (["--steps", "0"], "--steps 0"),
    (["--seeds", "0"], "--seeds 0"),
    (["--episodes", "0"], "--seeds 0"),
    (["--disturbance", "wobble"], "wobble"),
])
def test_bad_input_is_one_line(tmp_path, args, needle):
    r = _run(*args, "--out", str(tmp_path / "rl"), cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert needle in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "rl").exists()


def test_reference_only_needs_an_earlier_run(tmp_path):
    r = subprocess.run([sys.executable, str(SCRIPT), "--reference-only", "--out",
                        str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2
    assert "--reference-only needs a results.json" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
