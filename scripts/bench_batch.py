"""Many worlds per step, measured against an earlier commit on the same machine.

Each figure is measured in a fresh process pinned to one thread (BLAS, OpenMP and
torch), for this tree and for ``--against`` (a commit, checked out into a temporary git
worktree), alternately, ``--rounds`` times; the table gives each side's median, and
the ratios are of medians measured in the same rounds. The rows:

* **one seed**: ``ClosedLoop`` of the supervised KKL with the vehicle (align scenario,
  10 s, the paper's bench), microseconds per control step, and the physics floor of the
  same world (``mj_step`` over Te and the sensor's two ``mj_multiRay``);
* **64 seeds**: the same loop stepping 64 seeds together (1 s), control steps per
  second, beside ``mujoco.rollout`` stepping the same 64 worlds from the same states
  with the torques the loop applied, on one thread;
* **vector envs of 64 worlds** (``ledsim/LinkAlign-v0``, zero actions): Gymnasium's
  ``SyncVectorEnv`` and ``AsyncVectorEnv`` and, where the tree has it, the native one
  (``gym.make_vec``'s ``vector_entry_point``), steps per second; and the native one
  over ``mujoco.rollout`` stepping its own worlds, interleaved in one process.

    python scripts/bench_batch.py [--against 724fd71] [--rounds 3] [--quick]
                                  [--out docs/bench_batch.md] [--json PATH]

The commit's worktree needs git and the repository's history (a fresh clone has it).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ONE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                               "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")}
FIGURES = ("single_us", "floor_us", "batch_sps", "rollout_sps", "sync_sps", "async_sps",
           "native_sps", "native_over_rollout")


def measure(quick: bool) -> dict:
    """Every figure of the tree on ``sys.path`` (run in a fresh process)."""
    import warnings


    warnings.filterwarnings("ignore")
    out = {}
    from ledsim.loop.closed_loop import ClosedLoop
    from ledsim.loop.config import RunConfig  # the old path: both trees have it

    cfg = RunConfig(scenario="align", estimator="kkl", seconds=4.0 if quick else 10.0)
    loop = ClosedLoop(cfg, [0])
    t0 = time.perf_counter()
    loop.run()
    out["single_us"] = 1e6 * (time.perf_counter() - t0) / loop.steps
    out["floor_us"] = floor_us(loop.runs[0].world, 2.0 if quick else 5.0)
    n = 16 if quick else 64
    out["batch_sps"], out["rollout_sps"] = batch_against_rollout(n, 0.3 if quick else 1.0)
    out.update(_envs(n, 20 if quick else 60))
    if out.get("native_sps"):
        out["native_over_rollout"] = native_against_rollout(n, 20 if quick else 50,
                                                            3 if quick else 7)
    out["worlds"] = n
    return out


def native_against_rollout(n: int, steps: int, rounds: int) -> float:
    """The native vector env's steps / s over ``mujoco.rollout``'s on the same ``n``
    worlds, interleaved: each round times ``steps`` env steps (zero actions), then
    rollout stepping the env's worlds as they are for as many control periods (their
    controls held); the median of the rounds' ratios. Interleaving in one process
    keeps a slow spell of the machine out of the ratio."""
    import gymnasium as gym
    import mujoco
    import numpy as np
    from mujoco import rollout

    import ledsim.envs  # noqa: F401

    venv = gym.make_vec("ledsim/LinkAlign-v0", num_envs=n,
                        vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    a = np.zeros((n, 1), np.float32)
    venv.step(a)
    worlds = [e.world for e in venv.unwrapped.envs]
    m, sub = worlds[0].model, worlds[0].config.substeps
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    ratios = []
    with rollout.Rollout(nthread=0) as r:
        data = [mujoco.MjData(m)]
        for _ in range(rounds):
            t0 = time.perf_counter()
            for _ in range(steps):
                venv.step(a)
            env_sps = n * steps / (time.perf_counter() - t0)
            x0 = np.zeros((n, mujoco.mj_stateSize(m, full)))
            for i, w in enumerate(worlds):
                mujoco.mj_getState(w.model, w.data, x0[i], full)
            ctrl = np.repeat(np.stack([w.data.ctrl.copy() for w in worlds])[:, None, :],
                             steps * sub, axis=1)
            t0 = time.perf_counter()
            r.rollout([m] * n, data, x0, ctrl)
            ratios.append(env_sps / (n * steps / (time.perf_counter() - t0)))
    venv.close()
    return statistics.median(ratios)


def floor_us(world, seconds: float) -> float:
    """Microseconds per control step of the bare physics of ``world``: the substeps of
    one period and the sensor's ``mj_multiRay`` calls (one a photodiode: two on the
    paper's bench, five on a quad head), nothing else."""
    import mujoco
    import numpy as np

    from ledsim.physics.world import RAY_GROUPS

    m, d = world.model, world.data
    sub, n_rays = world.config.substeps, world.config.n_rays
    steps = int(round(seconds / world.config.constants.Te))
    geom, dist = np.zeros(n_rays, dtype=np.int32), np.zeros(n_rays)
    dirs = np.tile([1.0, 0.0, 0.0], n_rays)
    origins = [world.photodiode_pos(i).copy()
               for i in range(world.config.constants.layout.n_photodiodes)]
    body = world.ids.gimbal_body
    t0 = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d, nstep=sub)
        for o in origins:
            mujoco.mj_multiRay(m, d, o, dirs, RAY_GROUPS, 1, body, geom, dist, None, n_rays,
                               1.0)
    return 1e6 * (time.perf_counter() - t0) / steps


def batch_against_rollout(n: int, seconds: float, threads: int = 1,
                          estimator: str = "kkl", supervision: bool = True
                          ) -> tuple[float, float]:
    """(steps / s of the closed loop stepping ``n`` seeds of the align scenario, of
    ``mujoco.rollout`` stepping the same worlds open loop from the same states with the
    motor torques the loop applied and the thrusters at their start command), both on
    ``threads`` threads, measured in the same call."""
    import mujoco
    import numpy as np
    from mujoco import rollout

    from ledsim.loop.closed_loop import ClosedLoop
    from ledsim.loop.config import RunConfig  # the old path: both trees have it

    cfg = RunConfig(scenario="align", estimator=estimator, supervision=supervision,
                    seconds=seconds)
    loop = ClosedLoop(cfg, range(n), threads)
    worlds = [r.world for r in loop.runs]
    m = worlds[0].model
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    x0 = np.zeros((n, mujoco.mj_stateSize(m, full)))
    for i, w in enumerate(worlds):
        mujoco.mj_getState(w.model, w.data, x0[i], full)
    ctrl0 = np.stack([w.data.ctrl.copy() for w in worlds])
    t0 = time.perf_counter()
    outs = loop.run(keep_trace=True)
    wall = time.perf_counter() - t0
    sub = worlds[0].config.substeps
    ctrl = np.repeat(ctrl0[:, None, :], loop.steps * sub, axis=1)
    ctrl[..., worlds[0].ids.motor] = np.repeat(np.stack([o.trace.torque for o in outs]),
                                               sub, axis=1)
    data = [mujoco.MjData(m) for _ in range(threads)]
    with rollout.Rollout(nthread=threads if threads > 1 else 0) as r:
        t0 = time.perf_counter()
        r.rollout([m] * n, data, x0, ctrl)
        roll = time.perf_counter() - t0
    steps = n * loop.steps
    return steps / wall, steps / roll


def _envs(n: int, steps: int) -> dict:
    import gymnasium as gym
    import numpy as np

    import ledsim.envs  # noqa: F401

    out = {}
    spec = gym.spec("ledsim/LinkAlign-v0")
    modes = {"sync_sps": "sync", "async_sps": "async"}
    if getattr(spec, "vector_entry_point", None):
        modes["native_sps"] = "vector_entry_point"
    for key, mode in modes.items():
        venv = gym.make_vec("ledsim/LinkAlign-v0", num_envs=n, vectorization_mode=mode)
        venv.reset(seed=0)
        a = np.zeros((n, 1), np.float32)
        venv.step(a)
        t0 = time.perf_counter()
        for _ in range(steps):
            venv.step(a)
        out[key] = n * steps / (time.perf_counter() - t0)
        venv.close()
    return out


def _run_tree(tree: Path, quick: bool) -> dict:
    """:func:`measure` of ``tree`` in a fresh one-thread process."""
    env = {**os.environ, **ONE_THREAD, "MUJOCO_GL": "osmesa", "PYTHONPATH": str(tree)}
    with tempfile.NamedTemporaryFile(suffix=".json") as f:
        cmd = [sys.executable, __file__, "--measure", f.name] + (["--quick"] if quick else [])
        r = subprocess.run(cmd, env=env, cwd=tree, capture_output=True, text=True)
        if r.returncode:
            raise SystemExit(f"bench_batch: error: measuring {tree} failed:\n{r.stderr}")
        return json.loads(Path(f.name).read_text())


def _table(here: list[dict], there: list[dict], against: str, head: str) -> str:
    def med(rows, key):
        vals = [r[key] for r in rows if r.get(key) is not None]
        return statistics.median(vals) if vals else None

    h = {k: med(here, k) for k in FIGURES}
    t = {k: med(there, k) for k in FIGURES}
    n = here[0]["worlds"]

    def cell(v, fmt):
        return "-" if v is None else format(v, fmt)

    lines = [f"# Many worlds per step ({head} against {against}, measured alternately)", "",
             f"`python scripts/bench_batch.py --against {against}`: {len(here)} rounds "
             "alternating the two trees, each figure in a fresh process on one thread; "
             "medians. Ratios are of figures of the same tree measured in the same runs.",
             "", "| figure | " + against + " | " + head + " | " + head + " / " + against
             + " |", "|---|---|---|---|"]
    rows = [("one seed, supervised KKL with the vehicle [us per step]", "single_us", ".0f"),
            ("physics floor of that world [us per step]", "floor_us", ".1f"),
            (f"{n} seeds together, 1 thread [steps / s]", "batch_sps", ".3g"),
            (f"mujoco.rollout of the same {n} worlds [steps / s]", "rollout_sps", ".3g"),
            (f"SyncVectorEnv, {n} worlds [steps / s]", "sync_sps", ".3g"),
            (f"AsyncVectorEnv, {n} worlds [steps / s]", "async_sps", ".3g"),
            (f"native vector env, {n} worlds [steps / s]", "native_sps", ".3g")]
    for label, key, fmt in rows:
        ratio = h[key] / t[key] if h[key] is not None and t[key] else None
        lines.append(f"| {label} | {cell(t[key], fmt)} | {cell(h[key], fmt)} "
                     f"| {cell(ratio, '.2f')} |")
    lines += ["", "| ratio | " + against + " | " + head + " |", "|---|---|---|"]
    derived = [("floor / one seed's step (the loop's share of the floor)",
                lambda x: x["floor_us"] / x["single_us"]),
               (f"{n} seeds over mujoco.rollout", lambda x: x["batch_sps"] / x["rollout_sps"]),
               ("native vector env over SyncVectorEnv",
                lambda x: x["native_sps"] / x["sync_sps"] if x["native_sps"] else None),
               (f"native vector env over mujoco.rollout of {n} worlds",
                lambda x: x["native_sps"] / x["rollout_sps"] if x["native_sps"] else None),
               ("the same, interleaved in one process (median of the rounds' ratios)",
                lambda x: x.get("native_over_rollout"))]
    for label, f in derived:
        lines.append(f"| {label} | {cell(f(t) if t['single_us'] else None, '.2f')} "
                     f"| {cell(f(h), '.2f')} |")
    return "\n".join(lines) + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--against", default="724fd71", help="the commit to measure against")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="short runs, 16 worlds (a check)")
    ap.add_argument("--out", default=str(ROOT / "docs" / "bench_batch.md"))
    ap.add_argument("--json", metavar="PATH")
    ap.add_argument("--measure", metavar="JSON", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.measure:
        Path(args.measure).write_text(json.dumps(measure(args.quick)))
        return 0
    if args.rounds < 1:
        print(f"bench_batch: error: --rounds {args.rounds} is not allowed: must be >= 1",
              file=sys.stderr)
        return 2
    from ledsim.files.outputs import atomic_write_text

    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                          capture_output=True, text=True).stdout.strip() or "this tree"
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        r = subprocess.run(["git", "worktree", "add", "--detach", str(base), args.against],
                           cwd=ROOT, capture_output=True, text=True)
        if r.returncode:
            print(f"bench_batch: error: --against {args.against!r} is not a commit here: "
                  f"{r.stderr.strip().splitlines()[-1] if r.stderr.strip() else ''}",
                  file=sys.stderr)
            return 2
        try:
            here, there = [], []
            for k in range(args.rounds):
                print(f"round {k + 1}/{args.rounds}", file=sys.stderr, flush=True)
                there.append(_run_tree(base, args.quick))
                here.append(_run_tree(ROOT, args.quick))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT,
                           capture_output=True)
    text = _table(here, there, args.against, f"{head} + working tree"
                  if subprocess.run(["git", "diff", "--quiet", "HEAD"], cwd=ROOT).returncode
                  else head)
    atomic_write_text(Path(args.out), text)
    if args.json:
        atomic_write_text(Path(args.json), json.dumps({"here": here, "against": there},
                                                      indent=2) + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
