import json
import subprocess
import sys

import pytest
from conftest import assert_user_error, run_cli

from ledsim.cli import main


@pytest.mark.parametrize("args,needle", [
    (["--scenario", "nope"], "nope"),
    (["--scenario", "if1", "--distance", "0"], "--distance: 0 is not allowed"),
    (["--scenario", "if1", "--distance", "-0.1"], "--distance: -0.1 is not allowed"),
    (["--scenario", "if1", "--seeds", "0"], "--seeds 0"),
    (["--scenario", "if1", "--dphi", "0"], "--dphi 0"),
    (["--scenario", "if1", "--dphi-deg", "0"], "--dphi 0"),
    (["--scenario", "if1", "--distance", "nan"], "must be finite"),
    (["--scenario", "if1", "--dphi", "8"], "constants.dphi"),
    (["--scenario", "if1", "--distance", "0.15"], "no shipped checkpoint"),
    (["--scenario", "if1", "--checkpoint", "missing.pt"], "does not exist"),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, args, needle):
    out = tmp_path / "out"
    r = run_cli("evaluate", *args, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists() or not any(out.iterdir())


def test_checkpoint_for_other_constants_is_refused(tmp_path):
    r = run_cli("evaluate", "--scenario", "if1", "--distance", "0.2", "--checkpoint",
                "assets/checkpoints/kkl_d0.085.pt", "--out", str(tmp_path / "o"))
    assert r.returncode == 2
    assert "distance" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_corrupt_checkpoint_is_refused(tmp_path):
    bad = tmp_path / "bad.pt"
    bad.write_text("garbage")
    r = run_cli("evaluate", "--scenario", "if1", "--checkpoint", str(bad),
                "--out", str(tmp_path / "o"))
    assert r.returncode == 2 and "corrupt" in r.stderr


def test_evaluate_writes_results_table_and_figures(tmp_path, capsys):
    out = tmp_path / "ev"
    code = main(["evaluate", "--scenario", "if1", "--seeds", "2", "--starts", "2",
                 "--particles", "300", "--workers", "1", "--out", str(out)])
    assert code == 0
    res = json.loads((out / "results.json").read_text())
    assert res["scenario"] == "if1" and res["distance"] == 0.085 and res["seeds"] == 2
    assert set(res["estimators"]) >= {"kkl", "ekf", "ukf", "pf"}
    for e in res["estimators"].values():
        assert set(e["rmse"]) == {"x1", "x2", "y1", "y2"}
        assert set(e["rmse_steady"]) == {"x1", "x2", "y1", "y2"}
        assert 0 <= e["converged_fraction"] <= 1 and e["us_per_step"] > 0
    assert res["paper"]["x1"] == pytest.approx(7.2e-3)
    assert (out / "states.png").stat().st_size > 10_000
    assert (out / "powers.png").stat().st_size > 10_000
    assert "paper" in (out / "table.md").read_text()
    assert not list(out.glob(".*tmp"))


@pytest.mark.parametrize("args,needle", [
    (["--distance", "0"], "distance"),
    (["--torque-limit", "0"], "--torque-limit: 0 is not allowed"),
    (["--disturbance", "tornado"], "tornado"),
    (["--torque-profile", "wobble"], "wobble"),
    (["--seconds", "-1"], "--seconds"),
    (["--scene", "missing.xml"], "does not exist"),
    (["--led-yaw", "180"], "no line of sight"),
    (["--dphi", "0"], "dphi"),
    (["--led-yaw-deg", "180"], "no line of sight"),
    (["--gimbal-angle", "nan"], "must be finite"),
])
def test_simulate_bad_input_is_one_line_exit_2(tmp_path, args, needle):
    out = tmp_path / "sim"
    r = run_cli("simulate", *args, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists()


def test_simulate_writes_series_and_plot(tmp_path):
    import numpy as np

    out = tmp_path / "sim"
    code = main(["simulate", "--seconds", "1", "--torque-profile", "sine",
                 "--disturbance", "occlusion:start=0.3,duration=0.3", "--out", str(out)])
    assert code == 0
    data = np.load(out / "series.npz")
    assert data["phi"].shape == (100,) and data["power"].shape == (100, 2)
    assert data["occluded"].any()
    header = (out / "series.csv").read_text().splitlines()[0].split(",")
    assert {"t", "phi", "phidot", "power_1", "power_2", "occluded_1"} <= set(header)
    assert (out / "series.png").stat().st_size > 10_000


@pytest.mark.parametrize("args,needle", [
    (["--scenario", "dance"], "dance"),
    (["--estimator", "crystal-ball"], "crystal-ball"),
    (["--disturbance", "tornado"], "tornado"),
    (["--torque-limit", "0"], "--torque-limit"),
    (["--checkpoint", "assets/checkpoints/kkl_d0.085.pt"], "trained with"),
    (["--scene", "missing.xml"], "does not exist"),
    (["--seconds", "0"], "--seconds"),
])
def test_run_bad_input_is_one_line_exit_2(tmp_path, args, needle):
    out = tmp_path / "run"
    r = run_cli("run", "--seeds", "1", *args, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists()


def test_run_writes_results_and_plot(tmp_path):
    out = tmp_path / "run"
    code = main(["run", "--scenario", "align", "--estimator", "oracle", "--seeds", "1",
                 "--out", str(out)])
    assert code == 0
    res = json.loads((out / "results.json").read_text())
    assert res["estimator"] == "oracle" and res["availability"]["mean"] > 0.5
    assert (out / "run.png").stat().st_size > 10_000


def test_run_seconds_sets_the_length_of_a_run(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "--estimator", "oracle", "--seeds", "1", "--seconds", "2.5",
                 "--no-plot", "--out", str(out)]) == 0
    res = json.loads((out / "results.json").read_text())
    assert res["seconds"] == 2.5 and not (out / "run.png").exists()
    # Shorter than the steady-state window (from 5 s): its second half stands in for it,
    # rather than an empty column; the oracle's error there is zero.
    assert res["rmse_steady_x1"] == {"mean": 0.0, "std": 0.0, "n": 1}
    assert res["rmse_x1"]["n"] == 1
    # What is undefined stays undefined (null), not NaN: no event, no recovery.
    assert res["recovery_time"] == {"mean": None, "std": None, "n": 0}


def test_version_and_help_list_choices_and_defaults(capsys):
    import ledsim

    r = run_cli("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"ledsim {ledsim.__version__}"
    text = " ".join(run_cli("run", "--help").stdout.split())
    for word in ("align", "paper-closed-loop", "kkl", "ukf", "oracle", "vibration",
                 "occlusion", "identified", "default: 0.085"):
        assert word in text, word
    text = " ".join(run_cli("render", "--help").stdout.split())
    assert "side, overview, chase" in text and "osmesa" in text
    assert "low-light" in run_cli("train", "--help").stdout


def test_demo_with_a_missing_scene_is_one_line(tmp_path):
    r = run_cli("demo", "--seeds", "1", "--no-video", "--scene", "missing.xml",
                "--out", str(tmp_path / "d"))
    assert_user_error(r, "does not exist")


def test_results_on_stdout_progress_on_stderr_and_quiet_silences_it(tmp_path):
    args = ["run", "--estimator", "oracle", "--seeds", "1", "--seconds", "1", "--no-plot"]
    loud = run_cli(*args, "--out", str(tmp_path / "a"))
    assert loud.returncode == 0, loud.stderr
    assert "| align |" in loud.stdout and "it/s" not in loud.stdout
    assert "wrote" in loud.stderr and "| align |" not in loud.stderr
    quiet = run_cli(*args, "--quiet", "--out", str(tmp_path / "b"))
    assert quiet.returncode == 0 and quiet.stderr == ""
    assert "| align |" in quiet.stdout


def test_outputs_are_all_or_nothing(tmp_path, monkeypatch):
    """A failure half-way through writing leaves no folder and no temporary behind."""
    def broken_plot(*args, **kwargs):
        raise KeyboardInterrupt  # as if Ctrl-C hit between results.json and run.png

    monkeypatch.setattr("ledsim.experiment.plotting.plot_run", broken_plot)
    out = tmp_path / "run"
    code = main(["run", "--estimator", "oracle", "--seeds", "1", "--seconds", "1",
                 "--out", str(out)])
    assert code == 130 and not out.exists() and list(tmp_path.iterdir()) == []


def _children(pid: int) -> list[int]:
    from pathlib import Path

    kids = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        kids += [int(k) for k in (task / "children").read_text().split()]
    return kids


def _alive(pid: int) -> bool:
    from pathlib import Path

    try:
        return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_workers_die_with_their_parent(tmp_path):
    """SIGKILL of ``ledsim run --workers 2`` leaves no orphaned worker behind."""
    import os
    import signal
    import subprocess
    import sys
    import time

    proc = subprocess.Popen([sys.executable, "-m", "ledsim.cli", "run", "--estimator", "ekf",
                             "--seeds", "4", "--workers", "2", "--seconds", "60", "--quiet",
                             "--out", str(tmp_path / "r")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 60
        workers = []
        while time.time() < deadline and len(workers) < 2:
            time.sleep(0.2)
            workers = _children(proc.pid)
        assert len(workers) >= 2, "the workers never started"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        deadline = time.time() + 20
        while time.time() < deadline and any(_alive(w) for w in workers):
            time.sleep(0.2)
        assert not any(_alive(w) for w in workers)
    finally:
        proc.kill()


def test_train_design_deep_trains_a_gradient_decoder_of_two_layers(tmp_path):
    from ledsim.paper.model import LEDLinkModel
    from observer.kkl import checkpoint

    out = tmp_path / "deep.pt"
    r = run_cli("train", "--design", "deep", "--samples", "1000", "-q", "--out", str(out))
    assert r.returncode == 0, r.stderr
    from ledsim.constants import LinkConstants

    obs = checkpoint.load(out, LEDLinkModel(LinkConstants()))
    assert len(obs.decoder_T_star.mid) == 1
    assert obs.training_metadata["training"]["finetune_epochs"] == 20


@pytest.mark.parametrize("command,expected", [("run", "1"), ("sweep", "1"), ("train", "None")])
def test_blas_threads_are_pinned_before_numpy_loads_except_for_training(command, expected):
    import os
    import subprocess
    import sys

    code = ("import os, sys; import ledsim.cli as c; assert 'numpy' not in sys.modules; "
            f"c._pin_threads([{command!r}]); import numpy; "
            "print(os.environ.get('OPENBLAS_NUM_THREADS'))")
    env = {k: v for k, v in os.environ.items() if k not in
           ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True).stdout.strip()
    assert out == expected


def test_train_world_mujoco_makes_an_observer_that_run_loads(tmp_path):
    out = tmp_path / "m.pt"
    r = run_cli("train", "--world", "mujoco", "--samples", "2000", "-q", "--out", str(out))
    assert r.returncode == 0, r.stderr
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["data"]["source"].startswith("MuJoCo") and meta["system"]["class"] == \
        "GimbalSystem"
    r = run_cli("run", "--link", "paper", "--checkpoint", str(out), "--seeds", "1",
                "--seconds", "1",
                "--workers", "1", "--no-plot", "-q", "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr


def test_outputs_follow_the_umask(tmp_path):
    import os
    import stat

    env = {**os.environ, "MUJOCO_GL": "osmesa"}
    r = subprocess.run(["sh", "-c", "umask 022 && exec \"$0\" -m ledsim.cli run --seeds 1 "
                        "--seconds 1 --workers 1 -q --out \"$1\"", sys.executable,
                        str(tmp_path / "o")], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert stat.S_IMODE((tmp_path / "o").stat().st_mode) == 0o755
    for f in (tmp_path / "o").iterdir():
        assert stat.S_IMODE(f.stat().st_mode) == 0o644, f


def test_a_distance_the_shipped_kkl_does_not_serve_is_warned_about_and_flagged(tmp_path):
    r = run_cli("run", "--link", "paper", "--distance", "0.33", "--seeds", "1", "--seconds",
                "1", "--workers",
                "1", "--no-plot", "--out", str(tmp_path / "far"))
    assert r.returncode == 0, r.stderr
    assert "outside the 0.05-0.3 m" in r.stderr
    assert json.loads((tmp_path / "far" / "results.json").read_text())[
        "distance_served"] is False
    r = run_cli("run", "--distance", "0.5", "--seeds", "1", "--seconds", "1", "--workers",
                "1", "--no-plot", "-q", "--out", str(tmp_path / "near"))
    assert r.returncode == 0 and "outside" not in r.stderr
    assert json.loads((tmp_path / "near" / "results.json").read_text())["distance_served"]


def test_a_receiver_that_saturates_at_the_distance_is_refused(tmp_path):
    # bluecomm-200's PMT, its gain turned down 1024x: its peak fills the scale under
    # 0.57 m in coastal water (docs/saturation.md); 9 m, once clipped, no longer does.
    common = ("--link", "bluecomm-200", "--water", "coastal", "--seeds", "1", "--seconds",
              "0.2", "--workers", "1", "--no-plot", "-q")
    r = run_cli("run", *common, "--distance", "0.5", "--out", str(tmp_path / "near"))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "saturates at --distance 0.5" in r.stderr and "0.00102 W" in r.stderr
    assert "keep the range over 0.57 m" in r.stderr
    assert "Traceback" not in r.stderr and not (tmp_path / "near").exists()
    r = run_cli("run", *common, "--distance", "9", "--out", str(tmp_path / "far"))
    assert r.returncode == 0 and "saturates" not in r.stderr
    assert json.loads((tmp_path / "far" / "results.json").read_text())[
        "receiver_saturates"] is False
