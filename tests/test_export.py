"""The exported ONNX step is the numpy observer's step: onnxruntime against numpy over
10 s runs, in both worlds; bad export requests are refused in one line."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

onnx = pytest.importorskip("onnx")
ort = pytest.importorskip("onnxruntime")


def _replay(graph_bytes: bytes, obs, ys, us) -> float:
    """Largest |x_hat| difference between onnxruntime and ``obs`` on (ys, us)."""
    sess = ort.InferenceSession(graph_bytes, providers=["CPUExecutionProvider"])
    obs.reset()
    z = obs.z.copy()
    worst = 0.0
    for y, u in zip(ys, us, strict=True):
        x_np = obs.update(y)
        obs.predict(float(u))
        x_onnx, z = sess.run(None, {"z": z, "y": np.asarray(y, float),
                                    "u": np.array([u], float)})
        worst = max(worst, float(np.max(np.abs(x_onnx - x_np))))
    return worst


def test_the_closed_form_step_matches_numpy_with_inputs_and_dropouts():
    from ledsim import LEDLinkModel, LinkConstants
    from ledsim.paper import Noise, get_scenario, run
    from ledsim.paper.evaluate import default_checkpoint
    from observer.kkl import checkpoint
    from observer.kkl.export import kkl_step_graph

    model = LEDLinkModel(LinkConstants())
    kkl = checkpoint.load(default_checkpoint(0.085), model)
    sc = get_scenario("if2")
    out = run(model, sc, kkl, Noise.draw(model, sc.n_steps(model.Te), seed=0))
    ys = out.y[:1000].copy()  # 10 s
    ys[300:320, 0] = np.nan  # a dropout, held at h(x_hat)
    ys[500, 1] = 1e9  # an impossible power, held too
    graph = kkl_step_graph(kkl, model.step_form())
    onnx.checker.check_model(graph)
    assert _replay(graph.SerializeToString(), kkl, ys, out.u[:1000]) < 1e-6


def test_ledsim_export_writes_the_shipped_mujoco_step(tmp_path):
    from ledsim.experiment.estimators import build_estimator
    from ledsim.files.resources import require_shipped_checkpoint
    from ledsim.loop.build.estimation import identified_model
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig
    from ledsim.physics.gimbal_system import GimbalSystem

    out = tmp_path / "kkl.onnx"
    r = run_cli("export", "--format", "onnx", "--out", str(out), "-q")
    assert r.returncode == 0, r.stderr
    onnx.checker.check_model(onnx.load(str(out)))
    # 10 s of the MuJoCo loop's powers and inputs, replayed into both. A still hull:
    # the unsupervised KKL leaves its domain (phi_hat -1.6 rad at 5 s) under station
    # keeping's wander, where float32 and float64 part ways.
    cfg = RunConfig(estimator="kkl", supervision=False, seconds=10.0, imu=False,
                    station_keeping=False)
    trace = run_once(cfg, 0, keep_trace=True).trace
    system = GimbalSystem(cfg.world_config())
    model = identified_model(system)
    kkl = build_estimator("kkl", system, model=model,
                          checkpoint=require_shipped_checkpoint(0.085, "mujoco"))
    us = -trace.torque / system.inertia
    assert _replay(out.read_bytes(), kkl, trace.power, us) < 1e-6


@pytest.mark.parametrize("args,needle", [
    (["--format", "tflite"], "--format"),
    (["--checkpoint", "missing.pt"], "missing.pt"),
    (["--out", "x.txt"], ".onnx"),
])
def test_bad_export_requests_are_refused_in_one_line(tmp_path, args, needle):
    argv = ["export", *args]
    if "--out" not in args:
        argv += ["--out", str(tmp_path / "k.onnx")]
    r = run_cli(*argv, cwd=tmp_path)
    assert_user_error(r, needle)
    assert not (tmp_path / "k.onnx").exists()


def test_the_readmes_onnx_example_runs_without_ledsim(tmp_path):
    import re
    import subprocess
    import sys
    from pathlib import Path

    r = run_cli("export", "--out", str(tmp_path / "kkl.onnx"), "-q")
    assert r.returncode == 0, r.stderr
    text = (Path(__file__).resolve().parent.parent / "README.md").read_text()
    (code,) = re.findall(r"```py\n(.*?)```", text, flags=re.S)
    # A fresh interpreter that can import onnxruntime and numpy but not ledsim.
    code = "import sys\nsys.modules['ledsim'] = None\nsys.modules['observer'] = None\n" + code
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert len(r.stdout.strip().splitlines()) == 3


def test_the_pan_tilt_pair_exports_each_axis_and_matches_numpy(tmp_path):
    """``ledsim export --gimbal pan-tilt``: each axis's KKL as its own ONNX step on that
    axis's ratios, replayed through onnxruntime against numpy to 1e-6 over a driven axis
    with a dropout."""
    from ledsim.loop.build.head_kkl import AXES, reference_axes, shipped_axis
    from observer.kkl import checkpoint

    out = tmp_path / "pt.onnx"
    r = run_cli("export", "--gimbal", "pan-tilt", "--out", str(out), "-q")
    assert r.returncode == 0, r.stderr
    rng = np.random.default_rng(0)
    for name, system in zip(AXES, reference_axes(), strict=True):
        path = tmp_path / f"pt_{name}.onnx"
        onnx.checker.check_model(onnx.load(str(path)))
        obs = checkpoint.load(shipped_axis(name), system)
        x, ys, us = np.array([0.2, 0.0]), [], []
        for k in range(400):
            u = 2.0 * np.sin(0.05 * k)
            ys.append(system.h(x) * (1 + 1e-3 * rng.standard_normal(2)))
            us.append(u)
            x = system.f(x, u)
        ys = np.array(ys)
        ys[100:110, 0] = np.nan  # a dropout, held at h(x_hat)
        assert _replay(path.read_bytes(), obs, ys, us) < 1e-6, name
