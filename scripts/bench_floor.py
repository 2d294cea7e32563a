"""What a seed's control step costs at least, part by part, with many seeds together.

``scripts/bench_batch.py`` measures the loop of 64 seeds against ``mujoco.rollout`` of
the same worlds. This script asks how far that ratio can go: it runs the loop (the
supervised gain-scheduled KKL with the vehicle, align scenario, the paper's bench),
then times each part's own arithmetic on the states the run ended in, with nothing of
the loop around it (warm caches, one thread):

* **physics**: ``mujoco.rollout`` of the same worlds, per world and step;
* **the KKL's maps**: the calls a step makes (the wide decoder, the locked decoder, the
  encoder of the two states of the input correction), seed by seed as the loop makes
  them, and stacked over the seeds (rows of one grid gain through one product per
  layer; each row's interpolated output weights gathered first). Either way this is
  the float64 arithmetic of these networks, which any loop running this observer does;
* **the vehicle**: the stacked vehicles' step (``Vehicle.act_rows``), per vehicle;
* **the sensor**: every world's read in one pass (``SensorRows``, as the loop reads
  them), and each world's ray-cast read alone, per world;
* **the loop less its control steps**: what a control step that cost nothing would leave
  (a second run's time less its control steps' own, timed inside it), beside one
  world's bare physics (``bench_batch.floor_us``, the one-seed figure's floor, on a twin
  of world 0 just before and after that run).

The physics and the maps (the cheaper of the two ways) bound the steps per second of
any loop that runs this observer on this physics, however little Python it spends
around them; with the vehicle and the sensor as they are implemented, the last line
bounds a loop of these parts.

    python scripts/bench_floor.py [--seeds 64] [--out docs/bench_floor.md] [--json PATH]
    python scripts/bench_floor.py --seeds 1 --seconds 5 --out docs/bench_floor_one.md
"""

from __future__ import annotations

import os

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_k, "1")
os.environ.setdefault("MUJOCO_GL", "osmesa")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))


def _per_call(f, repeats: int) -> float:
    """Seconds per call of ``f`` (the best of three batches of ``repeats``)."""
    f()
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(repeats):
            f()
        best = min(best, (time.perf_counter() - t0) / repeats)
    return best


def _map_inputs(est):
    """The (z, w, s) of a KKL's next decoding and the two states its correction encodes."""
    f, xh = est.system.f, est._xhat
    return est.z, est.w, est.noise, np.stack([f(xh, 0.1), f(xh, est.u_bar)])


def maps_one_by_one(estimators) -> float:
    """Seconds per step of every seed's map calls, one seed at a time."""
    inputs = [_map_inputs(e) for e in estimators]

    def step():
        for e, (z, w, s, x2) in zip(estimators, inputs, strict=True):
            e.decoder_T_star(z, w, s)
            e.decoder_locked(z, w, s)
            e.encoder_T(x2[:, None], w)
    return _per_call(step, 20)


def _stacked(m, v: np.ndarray, ws, ss) -> np.ndarray:
    """``m`` (a :class:`~observer.kkl.gainmaps.GainTableMap`) of each row of ``v`` (N, 1,
    n_in) at its own gain and noise: the rows of one grid gain through one stacked
    product per layer."""
    out = np.empty((v.shape[0], m.n_out))
    picks = [m.weights(w, s) for w, s in zip(ws, ss, strict=True)]
    if m.shared:
        W = np.stack(picks)  # (N, n_out, H + 1)
        return (m.features(v) @ W.transpose(0, 2, 1))[:, 0]
    grid = np.array([p[0] for p in picks])
    for i in np.unique(grid):
        rows = np.flatnonzero(grid == i)
        a = np.array([picks[r][1] for r in rows])[:, None]
        lo = np.stack([picks[r][2] for r in rows]).transpose(0, 2, 1)
        hi = np.stack([picks[r][3] for r in rows]).transpose(0, 2, 1)
        near = (m.features(v[rows], i) @ lo)[:, 0]
        far = (m.features(v[rows], i + 1) @ hi)[:, 0]
        out[rows] = (1 - a) * near + a * far
    return out


def maps_stacked(estimators) -> float:
    """Seconds per step of the same calls, each map stacked over the seeds."""
    inputs = [_map_inputs(e) for e in estimators]
    z = np.stack([i[0] for i in inputs])[:, None]
    ws, ss = [i[1] for i in inputs], [i[2] for i in inputs]
    x2 = np.concatenate([i[3] for i in inputs])[:, None]
    e0 = estimators[0]

    def step():
        _stacked(e0.decoder_T_star, z, ws, ss)
        _stacked(e0.decoder_locked, z, ws, ss)
        _stacked(e0.encoder_T, x2, np.repeat(ws, 2), np.ones(2 * len(ws)))
    return _per_call(step, 20)


def measure(n: int, seconds: float) -> dict:
    from bench_batch import batch_against_rollout, floor_us

    from ledsim.loop.closed_loop import ClosedLoop
    from ledsim.loop.run_config import RunConfig
    from ledsim.physics.sensor_rows import SensorRows

    # One short run first: numba loads its compiled kernels from the cache on a
    # process's first step, which is not a step's cost.
    batch_against_rollout(n, min(seconds, 0.05))
    loop_sps, rollout_sps = batch_against_rollout(n, seconds)
    cfg = RunConfig(scenario="align", estimator="kkl", supervision=True, seconds=seconds)
    loop = ClosedLoop(cfg, range(n))
    # One world's bare physics, on a twin of world 0, just before and just after the
    # timed run: this machine's speed drifts within minutes.
    twin = ClosedLoop(cfg, [0]).runs[0].world
    burst = min(seconds, 1.0)
    before = floor_us(twin, burst)
    t0 = time.perf_counter()
    loop.run()
    run_us = 1e6 * (time.perf_counter() - t0) / (n * loop.steps)
    world_floor_us = 0.5 * (before + floor_us(twin, burst))
    estimators = [r.step.estimator for r in loop.runs]
    out = {"seeds": n, "seconds": seconds, "loop_sps": loop_sps, "rollout_sps": rollout_sps,
           "loop_us": 1e6 / loop_sps,
           "control_us": 1e6 * sum(r.spent for r in loop.runs) / (n * loop.steps),
           "physics_us": 1e6 / rollout_sps,
           "maps_one_by_one_us": 1e6 * maps_one_by_one(estimators) / n,
           "maps_stacked_us": 1e6 * maps_stacked(estimators) / n,
           "vehicle_us": 1e6 * _per_call(lambda: loop.vehicles.act_rows(seconds), 20) / n,
           "sensor_us": 1e6 * _per_call(SensorRows([r.sensor for r in loop.runs]).read,
                                        20) / n,
           "sensor_alone_us": 1e6 * _per_call(lambda: [r.sensor.read() for r in loop.runs],
                                              20) / n}
    # The stacked maps compute the seed-by-seed numbers (to round-off where a row's
    # interpolation weight is 0: a product by 0.0 is added instead of skipped).
    e, (z, w, s, _) = estimators[-1], _map_inputs(estimators[-1])
    one = e.decoder_T_star(z, w, s)
    stacked = _stacked(e.decoder_T_star, np.stack([z, z])[:, None], [w, w], [s, s])[0]
    out["maps_stacked_max_difference"] = float(np.max(np.abs(one - stacked)))
    out["maps_us"] = min(out["maps_one_by_one_us"], out["maps_stacked_us"])
    out["estimator_floor_us"] = out["physics_us"] + out["maps_us"]
    out["floor_us"] = out["estimator_floor_us"] + out["vehicle_us"] + out["sensor_us"]
    # Both from the same run: the machine's speed drifts between runs.
    out["loop_run_us"] = run_us
    out["loop_less_control_us"] = run_us - out["control_us"]
    out["world_floor_us"] = world_floor_us
    out["estimator_floor_sps"] = 1e6 / out["estimator_floor_us"]
    out["floor_sps"] = 1e6 / out["floor_us"]
    return out


def table(r: dict) -> str:
    n = r["seeds"]
    rows = [("the loop, measured", r["loop_us"], r["loop_sps"]),
            ("the loop again, timing its control steps", r["loop_run_us"],
             1e6 / r["loop_run_us"]),
            ("its control steps alone (gate to motor)", r["control_us"], None),
            ("the loop less its control steps", r["loop_less_control_us"],
             1e6 / r["loop_less_control_us"]),
            ("physics: `mujoco.rollout` of the same worlds", r["physics_us"],
             r["rollout_sps"]),
            ("physics of one world alone: `mj_step` over Te and the sensor's rays "
             "(`bench_batch.py`'s one-seed floor)", r["world_floor_us"], None),
            ("the KKL's maps, seed by seed", r["maps_one_by_one_us"], None),
            ("the KKL's maps, stacked over the seeds", r["maps_stacked_us"], None),
            ("the vehicle, stacked", r["vehicle_us"], None),
            ("the sensors, read in one pass (as the loop reads them)", r["sensor_us"],
             None),
            ("the sensors, world by world (each alone)", r["sensor_alone_us"], None),
            ("**physics and the maps** (the cheaper of the two)", r["estimator_floor_us"],
             r["estimator_floor_sps"]),
            ("**with the vehicle and the sensor** as they are", r["floor_us"],
             r["floor_sps"])]
    flags = "".join(f" --{k} {r[k]:g}" for k, default in (("seeds", 64), ("seconds", 1.0))
                    if r[k] != default)
    who = "one seed" if n == 1 else f"{n} seeds together"
    lines = [f"# What a seed-step costs at least ({who}, one thread)", "",
             f"`python scripts/bench_floor.py{flags}` (the module's docstring says how "
             "each part is timed). Microseconds per seed and step; steps per second where a "
             "figure is a rate.", "", "| part | us per seed-step | steps / s |",
             "|---|---|---|"]
    lines += [f"| {label} | {us:.1f} | {'' if sps is None else format(sps, '.3g')} |"
              for label, us, sps in rows]
    rate = r["rollout_sps"]
    lines += ["", "Over `mujoco.rollout`'s steps per second: the physics and the maps alone "
              f"reach {r['estimator_floor_sps'] / rate:.2f}, with the vehicle and the "
              f"sensor {r['floor_sps'] / rate:.2f}; the loop reaches "
              f"{r['loop_sps'] / rate:.2f}, {r['loop_sps'] / r['floor_sps']:.2f} of the "
              "second floor. A control step that cost nothing would leave the loop at "
              f"{1e6 / r['loop_less_control_us'] / rate:.2f} of `mujoco.rollout`"
              + (f" and at {r['world_floor_us'] / r['loop_less_control_us']:.2f} of its "
                 f"physics floor (the loop reaches {r['world_floor_us'] / r['loop_run_us']:.2f})"
                 if n == 1 else "")
              + ". The stacked maps' largest difference from the seed-by-seed call: "
              f"{r['maps_stacked_max_difference']:.1e}."]
    return "\n".join(lines) + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=64)
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--out", default=str(ROOT / "docs" / "bench_floor.md"))
    ap.add_argument("--json", metavar="PATH")
    args = ap.parse_args()
    for flag, v in (("--seeds", args.seeds), ("--seconds", args.seconds)):
        if not v > 0:
            print(f"bench_floor: error: {flag} {v} is not allowed: must be > 0",
                  file=sys.stderr)
            return 2
    import warnings

    warnings.filterwarnings("ignore")
    from ledsim.files.outputs import atomic_write_text

    r = measure(args.seeds, args.seconds)
    text = table(r)
    atomic_write_text(Path(args.out), text)
    if args.json:
        atomic_write_text(Path(args.json), json.dumps(r, indent=2) + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
