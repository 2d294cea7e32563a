"""An LED out of the yaw gimbal's plane is said before the run, with the pointing loss it
costs (issue 48): the oracle, handed the true phi, measures the same loss."""

import json

from conftest import run_cli


def _run(tmp_path, transmitter_depth: float, gimbal: str = "yaw"):
    out = tmp_path / f"tx{transmitter_depth:g}{gimbal}"
    r = run_cli("run", "--link", "luma", "--gimbal", gimbal, "--depth", "20", "--transmitter-depth",
                str(transmitter_depth), "--estimator", "oracle", "--seeds", "1",
                "--seconds", "1", "--no-plot", "--quiet", "--out", str(out))
    assert r.returncode == 0, r.stderr
    return r.stderr, json.loads((out / "results.json").read_text())


def test_an_led_20_deg_above_the_plane_is_said_with_the_loss_the_oracle_then_measures(
        tmp_path):
    stderr, results = _run(tmp_path, 10.0)
    notes = [line for line in stderr.splitlines() if "yaw gimbal's plane" in line]
    assert len(notes) == 1, stderr
    assert "19.5 deg above the yaw gimbal's plane" in notes[0]
    assert "expect an availability near 0" in notes[0]
    warned = float(notes[0].split(" dB of pointing loss")[0].rsplit(" ", 1)[1])
    measured = results["pointing_loss_db"]["mean"]
    assert abs(warned - measured) < 0.05, (warned, measured)
    assert results["availability"]["mean"] < 0.05


def test_a_small_elevation_is_said_without_a_verdict_and_a_level_link_not_at_all(tmp_path):
    stderr, _ = _run(tmp_path, 17.0)  # 5.7 deg: 0.11 dB, inside the availability's margin
    note = [line for line in stderr.splitlines() if "yaw gimbal's plane" in line]
    assert len(note) == 1 and "5.7 deg above" in note[0] and "expect" not in note[0]
    stderr, _ = _run(tmp_path, 18.5)  # 2.9 deg
    assert "yaw gimbal's plane" not in stderr


def test_the_pan_tilt_a_physical_link_points_by_default_is_not_warned(tmp_path):
    stderr, results = _run(tmp_path, 10.0, gimbal="pan-tilt")
    assert "gimbal's plane" not in stderr, stderr
    assert results["availability"]["mean"] > 0.9  # it turns to the LED
