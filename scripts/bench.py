"""Speed benchmarks (not tests): observer step costs, batched throughput, training time.

Ratios are measured in one run, next to absolute times, because this machine is noisy.
BLAS and torch run on one thread (pinned here, before numpy is imported) unless a row
says otherwise. Writes docs/bench.md (and prints it); ``--json PATH`` also writes the
headline figures as JSON.

    python scripts/bench.py [--quick] [--json PATH]
"""

from __future__ import annotations

import argparse
import os

from ledsim.experiment.montecarlo import WORKER_ENV  # imports no numpy

# Before numpy (and its BLAS) is imported: one thread, so "one core" means one core.
os.environ.update(WORKER_ENV)
os.environ.setdefault("MUJOCO_GL", "osmesa")
import json
import platform
import time
from pathlib import Path

import numpy as np
import torch
from bench_batch import batch_against_rollout, floor_us  # scripts/, beside this file

from ledsim.constants import LinkConstants
from ledsim.experiment.observer_presets import observer_preset
from ledsim.files.outputs import atomic_write_text
from ledsim.paper.evaluate import default_checkpoint
from ledsim.paper.model import LEDLinkModel
from observer import jit
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
from observer.kkl import checkpoint
from observer.kkl.training import train_kkl

ROOT = Path(__file__).resolve().parent.parent


def step_cost(est, ys, repeats=3, u: float = 0.0) -> float:
    """Median over repeats of the mean seconds for one update + predict (input ``u``;
    a KKL evaluates Omega only when u differs from u_bar = 0)."""
    times = []
    for _ in range(repeats):
        est.reset()
        t0 = time.perf_counter()
        for y in ys:
            est.update(y)
            est.predict(u)
        times.append((time.perf_counter() - t0) / len(ys))
    return float(np.median(times))


def batched_throughput(obs, n_traj=1024, n_steps=200, dtype=np.float32) -> float:
    """Observer steps per second (trajectories x steps / s), one core."""
    rng = np.random.default_rng(0)
    x = obs.system.sample_domain(rng, n_traj * n_steps)
    ys = obs.system.h(x).reshape(n_steps, n_traj, -1)
    obs.run_trajectories(ys[:10], dtype=dtype)  # warm up
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        obs.run_trajectories(ys, dtype=dtype)
        best = min(best, time.perf_counter() - t0)
    return n_traj * n_steps / best


def world_speed(timestep: float, seconds: float = 20.0, repeats: int = 3,
                integrator: str = "implicitfast") -> tuple[float, float]:
    """(control steps per second, real-time factor) of physics + ray sensor, open loop."""
    from ledsim.physics.sensor import IrradianceSensor
    from ledsim.physics.simulation import simulate
    from ledsim.physics.world import LinkWorld, WorldConfig

    world = LinkWorld(WorldConfig(timestep=timestep, integrator=integrator))
    sensor = IrradianceSensor(world)
    best = np.inf
    for _ in range(repeats):
        world.reset(0.1)
        t0 = time.perf_counter()
        simulate(world, sensor, seconds)
        best = min(best, time.perf_counter() - t0)
    steps = seconds / world.config.constants.Te
    return steps / best, seconds / best


def physics_floor(seconds: float = 10.0, repeats: int = 5) -> tuple[float, float]:
    """(control steps per second, real-time factor) of the bare physics floor, the best
    of ``repeats`` (:func:`bench_batch.floor_us`: the substeps of one control period and
    the sensor's two ``mj_multiRay`` calls)."""
    from ledsim.physics.world import LinkWorld

    world = LinkWorld()
    best = np.inf
    for _ in range(repeats):
        world.reset(0.1)
        world.set_torque(0.002)
        best = min(best, floor_us(world, seconds))
    return 1e6 / best, 1e6 / best * world.config.constants.Te


def head_floor_us(seconds: float = 10.0, repeats: int = 5) -> float:
    """Microseconds per control step of the bare physics of the CLI's default head's
    world (the pan-tilt with its quad on ``luma``, its vehicle's thrusters at rest): the
    substeps and its five photodiodes' ``mj_multiRay`` calls, the best of ``repeats``."""
    from ledsim.loop.run_config import RunConfig
    from ledsim.physics.world import LinkWorld

    world = LinkWorld(RunConfig(scenario="align", link="luma").world_config())
    best = np.inf
    for _ in range(repeats):
        world.reset()
        best = min(best, floor_us(world, seconds))
    return best


def rollout_speed(n_worlds: int, seconds: float = 5.0) -> float:
    """Control steps per second of ``mujoco.rollout`` stepping ``n_worlds`` copies of the
    scene open loop (physics only, one thread): the batched floor."""
    import mujoco
    from mujoco import rollout

    from ledsim.physics.world import LinkWorld

    world = LinkWorld()
    m, d = world.model, world.data
    substeps = round(world.config.constants.Te / m.opt.timestep)
    n_steps = int(seconds / m.opt.timestep)
    state = np.zeros(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    x0 = np.tile(state, (n_worlds, 1))
    ctrl = np.zeros((n_worlds, n_steps, m.nu))
    with rollout.Rollout(nthread=0) as r:
        r.rollout([m] * n_worlds, [d], x0, ctrl)  # warm up
        best = np.inf
        for _ in range(3):
            t0 = time.perf_counter()
            r.rollout([m] * n_worlds, [d], x0, ctrl)
            best = min(best, time.perf_counter() - t0)
    return n_worlds * n_steps / substeps / best


def batched_speed(n_worlds: int = 16, threads: int = 1, estimator: str = "kkl",
                  supervision: bool = False, seconds: float = 2.0,
                  repeats: int = 2) -> tuple[float, float]:
    """The best of ``repeats`` of :func:`bench_batch.batch_against_rollout`: (steps / s
    of the loop stepping ``n_worlds`` seeds, of ``mujoco.rollout`` replaying the same
    worlds), ``threads`` threads for both."""
    runs = [batch_against_rollout(n_worlds, seconds, threads, estimator, supervision)
            for _ in range(repeats)]
    return max(r[0] for r in runs), max(r[1] for r in runs)


def compiled_against_reference(repeats: int = 5) -> dict:
    """The supervised KKL on the compiled path (:mod:`observer.jit`) and on the numpy
    reference, alternately in this process, medians of ``repeats``: the 64 seeds' steps
    / s (0.5 s of the align scenario) against ``mujoco.rollout`` and one seed's us per
    step (10 s) with the KKL and with the EKF on the paper's bench, and with the CLI's
    default head (the pan-tilt with its quad on ``luma``), one thread. The reference path
    is the code before the compiled one (``scripts/fingerprint.py`` moves 0 runs with
    ``LEDSIM_COMPILED=0``)."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    rows = {True: [], False: []}
    one = {"kkl": RunConfig(scenario="align", estimator="kkl"),
           "ekf": RunConfig(scenario="align", estimator="ekf"),
           "default_head": RunConfig(scenario="align", link="luma")}
    for _ in range(repeats):
        for compiled in (False, True):
            with jit.use(compiled):
                b, r = batch_against_rollout(64, 0.5, 1, "kkl", True)
                us = {k: 1e4 / run_once(cfg, seed=0).realtime_factor
                      for k, cfg in one.items()}
            rows[compiled].append((b, r, us))
    out = {}
    for compiled, runs in rows.items():
        b, r = (float(np.median([run[i] for run in runs])) for i in range(2))
        med = {k: float(np.median([run[2][k] for run in runs])) for k in one}
        out["compiled" if compiled else "reference"] = {
            "steps_per_s_64": b, "rollout_steps_per_s_64": r, "ratio_64": b / r,
            "us_per_seed_step_64": 1e6 / b, "one_seed_us_per_step": med["kkl"],
            "one_seed_ekf_us_per_step": med["ekf"],
            "default_head_us_per_step": med["default_head"]}
    return out


def closed_loop_speed(estimator: str, integrator: str = "implicitfast") -> tuple[float, float]:
    """(real-time factor of the whole loop, estimator us per step), align scenario."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    best = None
    for _ in range(2):
        out = run_once(RunConfig(scenario="align", estimator=estimator,
                                 integrator=integrator), seed=0)
        if best is None or out.realtime_factor > best.realtime_factor:
            best = out
    return best.realtime_factor, best.us_per_step


def transition_speed(n: int = 20_000) -> dict[str, float]:
    """Microseconds per MuJoCo transition (``GimbalSystem.f`` and ``h`` of one state, as
    ``scripts/train_mujoco.py`` generates them): one at a time, and batched
    (``mujoco.rollout`` + a world batch) on 1 and 2 threads."""
    from ledsim.physics.gimbal_system import GimbalSystem
    from observer.kkl.training import generate_transitions

    out = {}
    for label, threads, batch_min in (("one at a time", 1, 10**12),
                                      ("batched, 1 thread", 1, None),
                                      ("batched, 2 threads", 2, None)):
        system = GimbalSystem(threads=threads)
        if batch_min:
            system.BATCH_MIN = batch_min
        generate_transitions(system, 500, 0.0, np.random.default_rng(1))  # warm up
        t0 = time.perf_counter()
        generate_transitions(system, n, 0.0, np.random.default_rng(0))
        out[label] = 1e6 * (time.perf_counter() - t0) / n
        system.close()
    return out


def short_run(plot: bool, seconds: float = 10.0, compiled: bool = True) -> dict:
    """Wall time [s] of ``ledsim run --seeds 1 --seconds S`` (align scenario) in a fresh
    process, the share of it spent simulating (S over the run's real-time factor), and
    whether torch was imported; ``compiled`` False: with ``LEDSIM_COMPILED=0``."""
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-X", "importtime", "-m", "ledsim", "run", "--seeds", "1",
               "--seconds", f"{seconds:g}", "-q", "--out", f"{tmp}/o"] + \
            ([] if plot else ["--no-plot"])
        t0 = time.perf_counter()
        env = dict(os.environ, LEDSIM_COMPILED="1" if compiled else "0")
        r = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env)
        wall = time.perf_counter() - t0
        res = json.loads(Path(f"{tmp}/o/results.json").read_text())
    sim = res["seconds"] / res["realtime_factor"]["mean"]
    torch_imported = any(line.rstrip().endswith("| torch") for line in r.stderr.splitlines())
    return {"seconds": seconds, "wall_s": wall, "simulating_s": sim,
            "simulating_share": sim / wall, "imports_torch": torch_imported,
            "compiled": compiled}


def short_runs(repeats: int = 3) -> dict:
    """:func:`short_run` of each row (plots on; 10 s and 60 s without plots on both
    paths), the rows alternately, ``repeats`` times: each figure the median of its
    runs (one fresh process is one sample of this machine's noise)."""
    rows = {"plots": (True, 10.0, True), "no_plot": (False, 10.0, True),
            "no_plot_reference": (False, 10.0, False), "no_plot_60s": (False, 60.0, True),
            "no_plot_60s_reference": (False, 60.0, False)}
    samples = {key: [] for key in rows}
    for _ in range(repeats):
        for key, (plot, seconds, compiled) in rows.items():
            samples[key].append(short_run(plot, seconds, compiled))
    out = {}
    for key, runs in samples.items():
        out[key] = dict(runs[0])
        for f in ("wall_s", "simulating_s", "simulating_share"):
            out[key][f] = float(np.median([r[f] for r in runs]))
        out[key]["repeats"] = repeats
    return out


def onnx_step_speed(steps: int = 2000) -> dict:
    """The exported KKL step (the shipped MuJoCo observer, with Omega) under onnxruntime
    against the numpy observer's update + predict, one thread each: us per step, and
    the file's size."""
    import onnxruntime as ort

    from ledsim.experiment.estimators import build_estimator
    from ledsim.files.resources import require_shipped_checkpoint
    from ledsim.loop.build.estimation import identified_model
    from ledsim.physics.gimbal_system import GimbalSystem
    from ledsim.physics.scene import WorldConfig
    from observer.kkl.export import kkl_step_graph

    system = GimbalSystem(WorldConfig())
    model = identified_model(system)
    kkl = build_estimator("kkl", system, model=model,
                          checkpoint=require_shipped_checkpoint(0.085, "mujoco"))
    data = kkl_step_graph(kkl, model.step_form()).SerializeToString()
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = opts.inter_op_num_threads = 1
    sess = ort.InferenceSession(data, opts, providers=["CPUExecutionProvider"])
    ys = model.h(np.stack([np.linspace(-0.2, 0.2, steps), np.zeros(steps)], -1))
    out = {}
    for name, u in (("without input", 0.0), ("with input (Omega)", 5.0)):
        kkl.reset()
        t0 = time.perf_counter()
        for y in ys:
            kkl.update(y)
            kkl.predict(u)
        t_np = (time.perf_counter() - t0) / steps
        z, uu = kkl.z.copy(), np.array([u])
        t0 = time.perf_counter()
        for y in ys:
            _, z = sess.run(None, {"z": z, "y": y, "u": uu})
        out[name] = {"numpy_us": 1e6 * t_np,
                     "onnxruntime_us": 1e6 * (time.perf_counter() - t0) / steps}
    out["file_bytes"] = len(data)
    return out


def import_floor() -> float:
    """Wall time [s] of a fresh Python that only imports numpy and mujoco."""
    import subprocess
    import sys

    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import numpy, mujoco"], check=True)
    return time.perf_counter() - t0


def render_speed(width: int = 640, height: int = 480, frames: int = 60) -> tuple[float, float]:
    """(frames/s with beam and overlay, frames/s of the bare MuJoCo render)."""
    from ledsim.physics.render import FrameRecorder
    from ledsim.physics.sensor import IrradianceSensor
    from ledsim.physics.world import LinkWorld

    world = LinkWorld()
    world.reset(0.2)
    sensor = IrradianceSensor(world)
    rec = FrameRecorder(world, width, height, 30, "side")
    try:
        world.forward_kinematics()
        reading = sensor.read()
        for _ in range(5):
            rec.render(0.0, reading)
        t0 = time.perf_counter()
        for k in range(frames):
            rec.overlay.push(reading.phi, reading.phi, *reading.power)
            rec.render(k / 30, reading)
        full = frames / (time.perf_counter() - t0)
        t0 = time.perf_counter()
        for _ in range(frames):
            rec.renderer.update_scene(world.data, camera="side")
            rec.renderer.render()
        bare = frames / (time.perf_counter() - t0)
    finally:
        rec.close()
    return full, bare


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="skip the training benchmark")
    ap.add_argument("--out", default=str(ROOT / "docs" / "bench.md"))
    ap.add_argument("--json", metavar="PATH", help="also write the headline figures as JSON")
    args = ap.parse_args()
    torch.set_num_threads(1)
    system = LEDLinkModel(LinkConstants())
    kkl = checkpoint.load(default_checkpoint(0.085), system)
    rng = np.random.default_rng(1)
    ys = system.h(np.stack([np.linspace(-0.2, 0.2, 2000), np.full(2000, 0.02)], -1))
    ys = ys + rng.normal(scale=system.measurement_noise_std[0], size=ys.shape)

    costs = {}
    for name, est in [("kkl", kkl), ("ekf", ExtendedKalmanFilter(system)),
                      ("ukf", UnscentedKalmanFilter(system)),
                      ("pf (5000)", ParticleFilter(system, 5000))]:
        n = 300 if name.startswith("pf") else 2000
        costs[name] = step_cost(est, ys[:n])
    costs["kkl with Omega (u != 0)"] = step_cost(kkl, ys, u=0.5)
    lines = ["# Benchmarks", "",
             f"`python scripts/bench.py` on {platform.machine()}, {os.cpu_count()} cores, "
             f"numpy {np.__version__}, torch {torch.__version__}; one thread.", "",
             "## One observer step (update + predict), single trajectory", "",
             "| estimator | us / step | cost relative to KKL |", "|---|---|---|"]
    for name, c in costs.items():
        lines.append(f"| {name} | {1e6 * c:.1f} | {c / costs['kkl']:.1f}x |")
    omega = costs["kkl with Omega (u != 0)"]
    lines += ["", "Where the KKL's cost advantage is real: a KKL step without input is a "
              "linear filter and one decoder pass, so it is "
              f"{costs['ekf'] / costs['kkl']:.0f}x cheaper than an EKF step here; with an "
              "input, Omega adds two encoder passes and two model steps, and the advantage "
              f"shrinks to {costs['ekf'] / omega:.1f}x (UKF: {costs['ukf'] / omega:.1f}x). "
              "Both baselines are Python on 2x2 matrices: their cost is call overhead, not "
              "arithmetic. In the closed loop the estimator is a minority of the step."]
    thr32 = batched_throughput(kkl, dtype=np.float32)
    thr64 = batched_throughput(kkl, dtype=np.float64)
    lines += ["", "## Batched KKL (1024 trajectories x 200 steps, one core)", "",
              "| decode precision | observer steps / s |", "|---|---|",
              f"| float32 | {thr32:.3g} |", f"| float64 | {thr64:.3g} |"]
    lines += ["", "## MuJoCo world: physics + ray-based sensor, open loop (one core)", "",
              "| physics timestep | substeps per Te | control steps / s | real-time factor |",
              "|---|---|---|---|"]
    floor = {}
    for dt in (0.002, 0.005, 0.01):
        sps, rtf = floor[dt] = world_speed(dt)
        lines.append(f"| {dt * 1e3:g} ms | {round(0.01 / dt)} | {sps:.3g} | {rtf:.0f}x |")
    bare_sps, bare_rtf = physics_floor()
    lines += ["", "The physics floor (the denominator of every ratio below): `mj_step` over "
              "one control period and the sensor's two `mj_multiRay` calls, nothing else: "
              f"{1e6 / bare_sps:.1f} us per control step, {bare_rtf:.0f}x real time. The "
              "open-loop rows above add the sensor's geometry and optics in Python."]
    n_roll = 64
    roll = rollout_speed(n_roll)
    lines += ["", f"`mujoco.rollout` of {n_roll} worlds, physics only, open loop, one "
              f"thread: {roll:.3g} control steps / s."]
    n_batch = 16
    batch_rows = {}
    for est, sup in (("oracle", False), ("kkl", False), ("ekf", False), ("ukf", False),
                     ("kkl", True)):
        for threads in (1, 2):
            batch_rows[est, sup, threads] = batched_speed(n_batch, threads, est, sup)
    big = batched_speed(64, 1, "kkl", True, seconds=1.0)
    lines += ["", f"## Many seeds stepped together ({n_batch} worlds, align scenario, 2 s)",
              "", "`ledsim.loop.closed_loop.ClosedLoop`: each seed runs the one control step "
              "(its own sensor, gate, supervisor, estimator and law: every seed's numbers "
              "are its single run's, bit for bit), and the physics of all worlds is "
              "split over the threads (one `MjData` each, MuJoCo without the GIL). The "
              "floor beside it is `mujoco.rollout` stepping the same "
              "worlds open loop, from the same states with the torques the loop applied, "
              "on as many threads, measured in the same call.", "",
              "| estimator | supervision | threads | closed-loop steps / s "
              "| rollout steps / s | ratio |", "|---|---|---|---|---|---|"]
    for (est, sup, threads), (b, r) in batch_rows.items():
        lines.append(f"| {est} | {'on' if sup else 'off'} | {threads} | {b:.3g} | {r:.3g} "
                     f"| {b / r:.2f} |")
    lines.append(f"| kkl (64 worlds, 1 s) | on | 1 | {big[0]:.3g} | {big[1]:.3g} "
                 f"| {big[0] / big[1]:.2f} |")
    head_b, head_r = batch_rows["kkl", False, 1]
    lines += ["", "The vehicles of all seeds (navigation sensors, aided INS, station "
              "keeping, line of sight) are stepped in one pass over their rows "
              "(`ledsim.agent.autopilot.Vehicle.stacked`), every row bit for bit its own "
              "vehicle's. The sensor, the supervisor and the estimator of each seed are "
              "still stepped one seed at a time, in Python under the GIL, so two threads "
              "gain little; they are most of a step. `docs/bench_batch.md` "
              "(`scripts/bench_batch.py`) measures these figures against an earlier "
              "commit, alternately on the same machine."]
    ab = compiled_against_reference()
    c, ref = ab["compiled"], ab["reference"]
    lines += ["", "## The compiled path against the numpy reference (supervised KKL, one "
              "thread)", "", f"Compiled kernels {'on' if jit.enabled() else 'off'} for the "
              "rest of this page (`observer/jit.py`; `LEDSIM_COMPILED=0` turns them off). "
              "Here both paths alternately in one process, medians of 5: the reference is "
              "the code before the compiled one, number for number.", "",
              "| path | 64 seeds: us per seed-step | steps / s | over `mujoco.rollout` "
              "| one seed: us per step | over the physics floor |", "|---|---|---|---|---|---|"]
    for name, r in (("numpy reference", ref), ("compiled", c)):
        lines.append(f"| {name} | {r['us_per_seed_step_64']:.0f} | {r['steps_per_s_64']:.3g} "
                     f"| {r['ratio_64']:.2f} | {r['one_seed_us_per_step']:.0f} "
                     f"| {1e6 / bare_sps / r['one_seed_us_per_step']:.2f} |")
    lines += ["", "Speed-up of the compiled path: "
              f"{ref['us_per_seed_step_64'] / c['us_per_seed_step_64']:.2f}x on 64 seeds, "
              f"{ref['one_seed_us_per_step'] / c['one_seed_us_per_step']:.2f}x on one seed.",
              "", "One seed's step (us) with the EKF on the same bench, and with the "
              "CLI's default head (`ledsim run`'s: the pan-tilt with its quad on `luma`: "
              "its sensor, per-axis KKLs and vehicle run compiled, its head supervisor "
              "does not yet):", "", "| path | EKF, paper's bench | default head |", "|---|---|---|"]
    head_floor = head_floor_us()
    for name, r in (("numpy reference", ref), ("compiled", c)):
        lines.append(f"| {name} | {r['one_seed_ekf_us_per_step']:.0f} "
                     f"| {r['default_head_us_per_step']:.0f} |")
    lines += ["", f"The default head's own physics floor (its substeps and its five "
              f"photodiodes' ray casts) is {head_floor:.1f} us a step: the compiled head "
              f"runs at {head_floor / c['default_head_us_per_step']:.2f} of it, the "
              f"reference at {head_floor / ref['default_head_us_per_step']:.2f}."]
    ab["default_head_floor_us"] = head_floor
    lines += ["", "## Closed loop in MuJoCo (align scenario, 10 s, one core)", "",
              "| estimator | real-time factor of the loop | over the physics floor "
              "| us per step | estimator us / step |", "|---|---|---|---|---|"]
    loop = {}
    for est in ("kkl", "ekf", "ukf", "pf", "oracle"):
        rtf, us = loop[est] = closed_loop_speed(est)
        lines.append(f"| {est} | {rtf:.0f}x | {rtf / bare_rtf:.2f} | {1e4 / rtf:.0f} "
                     f"| {us:.1f} |")
    trans = transition_speed()
    ref = trans["one at a time"]
    lines += ["", "## MuJoCo transitions for training (`scripts/train_mujoco.py`)", "",
              "One transition is `GimbalSystem.h` and `GimbalSystem.f` of one state. "
              "Batched, `f` runs the substeps in `mujoco.rollout` and reads phidot "
              "through a world batch, and `h` reads the vectorised sensor "
              "(`ledsim/physics/gimbal_system_batch.py`); the numbers are the same.", "",
              "| how | us per transition | speed-up |", "|---|---|---|"]
    for label, us in trans.items():
        lines.append(f"| {label} | {us:.1f} | {ref / us:.2f}x |")
    runs = short_runs()
    floor_import = import_floor()
    lines += ["", "## A short `ledsim run` (one seed, align scenario, the default head, "
              "fresh process)", "", "The rows run alternately, each figure the median of "
              f"{runs['plots']['repeats']} runs.", "",
              "| simulated [s] | plots | path | wall time [s] | simulating [s] "
              "| share simulating | imports torch |", "|---|---|---|---|---|---|---|"]
    for key, r in runs.items():
        lines.append(f"| {r['seconds']:g} | {'on' if key == 'plots' else '`--no-plot`'} "
                     f"| {'compiled' if r['compiled'] else '`LEDSIM_COMPILED=0`'} "
                     f"| {r['wall_s']:.2f} | {r['simulating_s']:.2f} "
                     f"| {r['simulating_share']:.0%} "
                     f"| {'yes' if r['imports_torch'] else 'no'} |")
    lines += ["", "The rest is Python's start, importing numpy and MuJoCo, building the "
              "scene, fitting the identified model (4000 transitions, batched), on the "
              "compiled path importing numba and loading the cached kernels and, with "
              "plots, importing matplotlib and drawing. The shipped observers load "
              "without torch (`.safetensors` files). A fresh Python that only imports "
              f"numpy and MuJoCo takes {floor_import:.2f} s: longer than the 10 s run "
              "simulates, so only longer runs can spend most of their time simulating. "
              "On the compiled path a process pays once for numba's import and its "
              "first cached kernel's load (about half a second), which a run earns back "
              "by simulating faster: the 10 s run's wall time is "
              f"{runs['no_plot']['wall_s']:.2f} s against "
              f"{runs['no_plot_reference']['wall_s']:.2f} s on the reference, the 60 s "
              f"run's {runs['no_plot_60s']['wall_s']:.2f} s against "
              f"{runs['no_plot_60s_reference']['wall_s']:.2f} s."]
    ox = onnx_step_speed()
    lines += ["", "## The exported observer (`ledsim export`, one step, one thread)", "",
              "The shipped MuJoCo KKL as an ONNX graph (float64) under onnxruntime, against "
              "the numpy observer's update + predict on the same powers. File size: "
              f"{ox['file_bytes'] / 1024:.0f} KiB.", "",
              "| step | numpy us | onnxruntime us | onnxruntime / numpy |", "|---|---|---|---|"]
    for key in ("without input", "with input (Omega)"):
        r = ox[key]
        lines.append(f"| {key} | {r['numpy_us']:.1f} | {r['onnxruntime_us']:.1f} "
                     f"| {r['onnxruntime_us'] / r['numpy_us']:.2f} |")
    full, bare = render_speed()
    lines += ["", f"## Rendering ({os.environ.get('MUJOCO_GL', 'default')} backend, "
              "640x480, side camera)", "", "| what | frames / s |", "|---|---|",
              f"| frame with beams and overlay panel | {full:.1f} |",
              f"| bare MuJoCo render of the same scene | {bare:.1f} |"]
    if not args.quick:
        torch.set_num_threads(2)
        design, cfg = observer_preset("default", system.Te)
        _, rep = train_kkl(system, design, cfg, progress=False)
        lines += ["", "## Training the default observer (2 threads)", "",
                  f"{rep.seconds:.1f} s for {cfg.n_samples} samples "
                  f"(L_dyn = {rep.loss_dyn:.2e}, L_recon = {rep.loss_recon:.2e})"]
    text = "\n".join(lines) + "\n"
    atomic_write_text(Path(args.out), text)
    print(text)
    if args.json:
        figures = {
            "floor_rtf": bare_rtf, "floor_steps_per_s": bare_sps,
            "open_loop_sensor_rtf": floor[0.002][1],
            "loop_rtf": {k: v[0] for k, v in loop.items()},
            "floor_ratio_single": loop["kkl"][0] / bare_rtf,
            "kkl_over_ekf_loop_speed": loop["kkl"][0] / loop["ekf"][0],
            "rollout_steps_per_s": roll, "rollout_worlds": n_roll,
            # KKL without supervision, one thread, 16 worlds, against mujoco.rollout.
            "batched_steps_per_s": head_b, "floor_ratio_batched": head_b / head_r,
            "batched_rollout_steps_per_s": head_r, "batched_worlds": n_batch,
            "batched": [{"estimator": e, "supervision": s, "threads": t,
                         "steps_per_s": b, "rollout_steps_per_s": r, "ratio": b / r}
                        for (e, s, t), (b, r) in batch_rows.items()],
            # the 64 seeds' supervised KKL (what users sweep and train on), one thread
            "supervised_64": {"worlds": 64, "steps_per_s": big[0],
                              "rollout_steps_per_s": big[1], "ratio": big[0] / big[1],
                              "us_per_seed_step": 1e6 / big[0],
                              "rollout_us_per_seed_step": 1e6 / big[1]},
            "one_seed_us_per_step": 1e4 / loop["kkl"][0], "floor_us": 1e6 / bare_sps,
            "compiled": jit.enabled(), "compiled_against_reference": ab,
            "render_fps": full, "render_fps_bare": bare,
            "transitions_us": trans, "transitions_speedup": ref / trans["batched, 2 threads"],
            "short_run": runs, "import_numpy_mujoco_s": floor_import, "onnx_step": ox,
            "threads": {"blas": os.environ["OPENBLAS_NUM_THREADS"], "torch": 1}}
        atomic_write_text(Path(args.json), json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main()
