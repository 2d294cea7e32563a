"""Records that replay: a saved trace holds what its estimator was given, and a fresh
estimator (or an ONNX export of it) given the same gives the same estimates."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.files.resources import require_shipped_checkpoint
from ledsim.loop.closed_loop import run_once
from ledsim.loop.replay import ReplayError, replay
from ledsim.loop.run_config import RunConfig

OCCLUSION = ("occlusion:start=2,duration=1",)


def _save(tmp_path, name="t", seconds_=4.0, **kw):
    cfg = RunConfig(seconds=seconds_, disturbances=OCCLUSION, particles=300, **kw)
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


@pytest.mark.parametrize("kw, export", [
    (dict(estimator="kkl"), ["--checkpoint", str(require_shipped_checkpoint(
        0.085, "mujoco", "scheduled"))]),  # the bench's default, gain-scheduled
    (dict(estimator="kkl", link="luma", seconds_=3.0), ["--gimbal", "pan-tilt"]),
], ids=["scheduled", "pan-tilt"])
def test_the_default_kkl_replays_through_its_onnx_export_to_1e_6(tmp_path, kw, export):
    """What ``kkl`` runs by default: on the bench the gain-scheduled KKL (its maps in the
    graph, its schedule beside it); on a physical link the pan-tilt's pair (one exported
    step per axis, on that axis's ratios)."""
    pytest.importorskip("onnxruntime")
    path, _ = _save(tmp_path, **kw)
    onnx = tmp_path / "kkl.onnx"
    r = run_cli("export", *export, "--out", str(onnx), "-q")
    assert r.returncode == 0, r.stderr
    r = run_cli("replay", str(path), "--onnx", str(onnx), "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["against"] == "onnx" and res["estimates"] >= 150
    assert res["max_abs_difference"] <= 1e-6
    if "--gimbal" in export:  # a missing half is refused in one line
        (tmp_path / "kkl_elevation.onnx").unlink()
        assert_user_error(run_cli("replay", str(path), "--onnx", str(onnx)),
                          "kkl_elevation.onnx' does not exist")
    else:  # the maps of another observer are refused
        other = tmp_path / "fixed.onnx"
        r = run_cli("export", "--out", str(other), "-q")
        assert r.returncode == 0, r.stderr
        assert_user_error(run_cli("replay", str(path), "--onnx", str(other)),
                          "is not the maps of a gain-scheduled KKL")


def test_replay_refuses_what_it_cannot_replay_in_one_line(tmp_path):
    path, _ = _save(tmp_path, estimator="ekf")
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
    r = run_cli("run", "--gimbal", "yaw",
                "--estimator", "ekf", "--disturbance", OCCLUSION[0], "--seconds",
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


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """A short trace of the EKF: its path and its arrays."""
    cfg = RunConfig(estimator="ekf", seconds=1.0, particles=300)
    series = run_once(cfg, 1, keep_trace=True).trace.series()
    path = tmp_path_factory.mktemp("trace") / "ekf.npz"
    np.savez_compressed(path, **series)
    return path, series


class _Payload:
    """What an unpickled object array would run: touch a marker."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


def _hostile(path, series, case, tmp_path):
    """Write the damaged or foreign file of ``case`` at ``path``; returns a needle of its
    error."""
    data = path.read_bytes()
    cfg = json.loads(str(series["config"]))

    def variant(needle, **changes):
        np.savez(out, **{k: v for k, v in {**series, **changes}.items() if v is not None})
        return needle

    out = tmp_path / f"{case}.npz"
    if case == "truncated":
        out.write_bytes(data[:len(data) // 2])
        return "damaged"
    if case == "bad crc":  # a byte of the record's data flipped (stored, not deflated)
        np.savez(out, **series)
        raw = bytearray(out.read_bytes())
        raw[raw.index(b"call_args.npy") + 400] ^= 0xFF
        out.write_bytes(bytes(raw))
        return "CRC-32"
    if case == "empty":
        out.write_bytes(b"")
        return "is empty"
    if case == "json":
        out.write_text(json.dumps(cfg))
        return "not a .npz trace"
    if case == "random":
        out.write_bytes(np.random.default_rng(0).bytes(4096))
        return "not a .npz trace"
    if case == "npy":
        np.save(out, series["phi"])
        out.write_bytes(out.with_suffix(".npz.npy").read_bytes())
        return "one .npy array"
    if case == "directory":
        out.mkdir()
        return "is not a file"
    if case == "missing":
        return "does not exist"
    if case == "no record":
        return variant("--save-trace", call_kind=None, call_args=None)
    if case == "config not json":
        return variant("is not JSON", config=np.array("{estimator: ekf"))
    if case == "config a list":
        return variant("JSON object", config=np.array("[1, 2]"))
    if case == "config unknown key":
        return variant("unknown key 'warp'", config=np.array(json.dumps({**cfg, "warp": 9})))
    if case == "config wrong type":
        return variant("distance 'far' is not allowed",
                       config=np.array(json.dumps({**cfg, "distance": "far"})))
    if case == "config bad value":
        return variant("--distance -1 is not allowed",
                       config=np.array(json.dumps({**cfg, "distance": -1})))
    if case == "config unknown estimator":
        return variant("unknown estimator 'crystal-ball'",
                       config=np.array(json.dumps({**cfg, "estimator": "crystal-ball"})))
    if case == "config missing checkpoint":
        return variant("checkpoint", config=np.array(json.dumps(
            {**cfg, "estimator": "kkl", "checkpoint": str(tmp_path / "gone.pt")})))
    if case == "object array":
        return variant("Python objects", call_args=np.array(
            [_Payload(tmp_path / "pwned")] * 3, dtype=object))
    if case == "object config":
        return variant("Python objects", config=np.array({"a": 1}, dtype=object))
    if case == "args of one dimension":
        return variant("not floats in 2 dimensions", call_args=series["call_args"].ravel())
    if case == "kinds of floats":
        return variant("not integers", call_kind=series["call_kind"].astype(float))
    if case == "config a number":
        return variant("not a string", config=np.array(3.0))
    if case == "rows differ":
        return variant("different numbers of calls", call_step=series["call_step"][:-1])
    kind, nargs = series["call_kind"].copy(), series["call_nargs"].copy()
    if case == "unknown call":
        kind[3] = 17
        return variant("not one of", call_kind=kind)
    if case == "too many arguments":
        nargs[3] = 99
        return variant("more arguments than", call_nargs=nargs)
    if case == "an update of one number":
        nargs[np.flatnonzero(kind == 2)[0]] = 1
        return variant("(update) has 1 arguments", call_nargs=nargs)
    if case == "estimates of three states":
        return variant("call_out has 3 columns", call_out=np.zeros((len(kind), 3)))
    if case == "a NaN input":
        args = series["call_args"].copy()
        args[np.flatnonzero(kind == 3)[0], 0] = np.nan
        return variant("NaN or infinite", call_args=args)
    raise AssertionError(case)


HOSTILE = ["truncated", "bad crc", "empty", "json", "random", "npy", "directory", "missing",
           "no record", "config not json", "config a list", "config unknown key",
           "config wrong type", "config bad value", "config unknown estimator",
           "config missing checkpoint", "object array", "object config",
           "args of one dimension", "kinds of floats", "config a number", "rows differ",
           "unknown call", "too many arguments", "an update of one number",
           "estimates of three states", "a NaN input"]


@pytest.mark.parametrize("case", HOSTILE)
def test_a_damaged_or_foreign_trace_is_one_line_and_exit_2(saved, case, tmp_path, capsys):
    from ledsim.cli import main

    needle = _hostile(*saved, case, tmp_path)
    out = tmp_path / f"{case}.npz"
    assert main(["replay", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"ledsim: error: trace {str(out)!r}") and needle in err, err
    assert len(err.strip().splitlines()) == 1 and "allow_pickle" not in err, err
    assert not (tmp_path / "pwned").exists()


def test_a_damaged_trace_from_the_command_line(saved, tmp_path):
    """No traceback and no advice to load unsafely, in a fresh process."""
    for case in ("truncated", "object array", "json"):
        needle = _hostile(*saved, case, tmp_path)
        r = run_cli("replay", str(tmp_path / f"{case}.npz"))
        assert_user_error(r, needle)
        assert "allow_pickle" not in r.stderr


def test_a_trace_of_a_pt_checkpoint_name_replays(tmp_path):
    """Traces saved before the checkpoints were converted name the .pt files."""
    ckpt = require_shipped_checkpoint(0.085, "mujoco")
    path, _ = _save(tmp_path, estimator="kkl", checkpoint=str(ckpt.with_suffix(".pt")),
                    seconds_=3.0)
    assert replay(path).max_abs_difference == 0.0


def test_a_saved_run_configuration_reads_back_and_is_checked():
    from dataclasses import asdict

    from ledsim.errors import LedsimError

    cfg = RunConfig(disturbances=OCCLUSION, imu_noise=("dvl_noise=0.02",), seconds=3.0,
                    initial_angle=0.1, water="coastal", link="aquaoptical")
    assert RunConfig.from_dict(json.loads(json.dumps(asdict(cfg)))) == cfg
    assert RunConfig.from_dict({"estimator": "ekf"}) == RunConfig(estimator="ekf")  # older
    for saved, needle in (({"seeds": 2.0}, "an integer"), ({"imu": "yes"}, "true or false"),
                          ({"seconds": True}, "a number or null"), ({"x": 1}, "'x'"),
                          ({"scenario": "dance"}, "dance")):
        with pytest.raises(LedsimError, match=needle):
            RunConfig.from_dict(saved)
