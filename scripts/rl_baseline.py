"""An RL baseline on ledsim/LinkAlign-v0: PPO (8 stacked observations) and RecurrentPPO
(an LSTM policy), against the shipped stack of ``ledsim run`` (KKL under supervision,
cascade PI) and the oracle, on the same seeds and disturbances.

    python scripts/rl_baseline.py [--steps 200000] [--disturbance SPEC]... [--episodes 20]
                                  [--vector-envs N] --out DIR   # needs 'ledsim[rl,train]'

``--vector-envs N`` trains on the native vector env (N worlds stepped in one call,
``gym.make_vec``) through :mod:`ledsim.envs.sb3`'s adapter, with 1024 transitions per
update as with one env.

Training episodes start from a random misalignment in +-0.3 rad (``scenario=None``);
evaluation episodes are seeds 100.. of ``ledsim run --scenario align``, from each start
of :data:`STARTS`: the scenario's 0.3 rad, and two PPO was not trained on, 1.0 rad
(outside the field of view) and -0.45 rad (``reset(options={"initial_angle": ...})``).
Writes ``DIR/results.json`` (per policy: ``availability``, the share of the steps with
at least 90 % of the achievable power, as ``ledsim run`` counts it, and
``availability_steady`` from 5 s on, ``mean_return``, the mean episode return of the
reward in [0, 1] per step, all from 0.3 rad; ``starts``: each start's per-episode
availabilities; ``train_seconds``; ``env_steps``), the trained policies
(``DIR/ppo.zip``, ``DIR/recurrent_ppo.zip``) and ``DIR/learning_curve.png``. The shipped
stack and the oracle are evaluated with both acquisitions (``warm-up``,
``minimum-time``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from ledsim.experiment.montecarlo import WORKER_ENV  # imports no numpy

os.environ.update(WORKER_ENV)  # one BLAS thread: the env is the cost, not the network
os.environ.setdefault("MUJOCO_GL", "osmesa")

import numpy as np  # noqa: E402

import ledsim.envs  # noqa: E402,F401 (registers the env)
from ledsim.errors import LedsimError  # noqa: E402
from ledsim.files.outputs import atomic_write_text, check_out_dir, output_folder  # noqa: E402
from ledsim.physics.disturbances import parse_disturbance  # noqa: E402

EVAL_SEED0 = 100
AVAILABLE = 0.9  # reward (share of the achievable power) counted as available
STEADY_STEP = 500  # the steady window of ledsim run: from 5 s
#: Evaluation starts: the align scenario's own (0.3 rad), and two PPO never saw.
STARTS = {"0.3": None, "1.0": 1.0, "-0.45": -0.45}


def make_env(disturbances, scenario=None, stack: int = 1, acquisition: str | None = None):
    import gymnasium as gym
    from gymnasium.wrappers import FrameStackObservation

    extra = {} if acquisition is None else {"acquisition": acquisition}
    env = gym.make("ledsim/LinkAlign-v0", scenario=scenario, disturbances=disturbances,
                   **extra)
    return FrameStackObservation(env, stack) if stack > 1 else env


def episode(policy_for, disturbances, seed: int, start, stack: int = 1,
            acquisition: str | None = None) -> np.ndarray:
    """The rewards of one align episode (seed ``seed``, from ``start`` [rad]; None: the
    scenario's) of the policy ``policy_for(env)`` gives for the episode's env."""
    env = make_env(disturbances, "align", stack, acquisition)
    act = policy_for(env)
    options = None if start is None else {"initial_angle": start}
    obs, _ = env.reset(seed=seed, options=options)
    rewards, done = [], False
    while not done:
        obs, r, term, trunc, _ = env.step(act(obs))
        rewards.append(r)
        done = term or trunc
    env.close()
    return np.array(rewards)


def evaluate(policy_for, disturbances, seeds: int, stack: int = 1,
             acquisition: str | None = None) -> dict:
    """``availability`` (over the episode, and ``availability_steady`` from 5 s, after
    any alignment) and ``mean_return`` over ``seeds`` episodes of the align scenario
    (seeds 100..) from 0.3 rad, and ``starts``: each start's per-episode availability."""
    starts = {}
    for name, start in STARTS.items():
        runs = [episode(policy_for, disturbances, EVAL_SEED0 + k, start, stack,
                        acquisition) for k in range(seeds)]
        starts[name] = [float(np.mean(r >= AVAILABLE)) for r in runs]
        if start is None:
            steady = [float(np.mean(r[STEADY_STEP:] >= AVAILABLE)) for r in runs]
            returns = [float(r.sum()) for r in runs]
    return dict(availability=float(np.mean(starts["0.3"])),
                availability_steady=float(np.mean(steady)),
                mean_return=float(np.mean(returns)), starts=starts)


def model_policy(model, recurrent: bool):
    """``policy_for(env)`` of a trained model (a recurrent one keeps its LSTM state)."""
    def policy_for(env):
        memory = {"state": None, "start": True}

        def act(obs):
            if not recurrent:
                return model.predict(obs, deterministic=True)[0]
            action, memory["state"] = model.predict(
                obs, state=memory["state"], episode_start=np.array([memory["start"]]),
                deterministic=True)
            memory["start"] = False
            return action
        return act
    return policy_for


def vector_env(disturbances, stack: int, num_envs: int):
    """The native vector env (``num_envs`` worlds, one call a step) for
    stable-baselines3, frame-stacked ``stack`` deep, with :class:`Monitor`'s episode
    record."""
    from stable_baselines3.common.vec_env import VecFrameStack

    from ledsim.envs.sb3 import EpisodeRecord, make_sb3_vec_env

    venv = make_sb3_vec_env(num_envs=num_envs, scenario=None, disturbances=disturbances)
    return EpisodeRecord(VecFrameStack(venv, stack) if stack > 1 else venv)


def train(name: str, steps: int, disturbances, seed: int = 0, vector_envs: int = 0):
    """(model, seconds, episode returns as (env steps, return) pairs); ``vector_envs``
    N > 0: on the native vector env of N worlds (0: one env)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.monitor import Monitor

    stack = 8 if name == "ppo" else 1
    env = vector_env(disturbances, stack, vector_envs) if vector_envs else \
        Monitor(make_env(disturbances, None, stack))
    # n_steps is per env: the same 1024 transitions per update whatever the worlds.
    common = dict(seed=seed, device="cpu", verbose=0,
                  n_steps=max(1024 // max(vector_envs, 1), 1), batch_size=256,
                  gamma=0.99, learning_rate=3e-4)
    if name == "ppo":
        model = PPO("MlpPolicy", env, **common)
    else:
        from sb3_contrib import RecurrentPPO

        model = RecurrentPPO("MlpLstmPolicy", env, **common)
    t0 = time.perf_counter()
    model.learn(steps)
    seconds = time.perf_counter() - t0
    lengths = np.cumsum(env.get_episode_lengths())
    curve = list(zip(lengths.tolist(), env.get_episode_rewards(), strict=True))
    env.close()
    return model, seconds, curve


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=200_000, help="training steps per policy")
    ap.add_argument("--disturbance", action="append", default=[], metavar="SPEC",
                    help="ledsim run's disturbance syntax (repeatable)")
    ap.add_argument("--episodes", "--seeds", dest="seeds", type=int, default=20,
                    help="evaluation episodes per start (seeds 100..)")
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--vector-envs", type=int, default=0, metavar="N",
                    help="train on the native vector env of N worlds stepped in one call "
                    "(gym.make_vec, through ledsim.envs.sb3's adapter); 0: one env")
    ap.add_argument("--reference-only", action="store_true",
                    help="re-evaluate only the shipped stack and the oracle in the "
                    "results.json already in --out, keeping its trained policies' rows "
                    "(the RL policies do not use ledsim's estimator: a change of it "
                    "moves only these rows)")
    args = ap.parse_args()
    if args.reference_only:
        return reference_only(Path(args.out), args.seeds)
    try:
        if args.steps < 1:
            raise LedsimError(f"--steps {args.steps} is not allowed: must be >= 1")
        if args.vector_envs < 0:
            raise LedsimError(f"--vector-envs {args.vector_envs} is not allowed: must be "
                              ">= 0")
        if args.seeds < 1:
            raise LedsimError(f"--episodes/--seeds {args.seeds} is not allowed: must be >= 1")
        for d in args.disturbance:
            parse_disturbance(d)
        out = check_out_dir(args.out)
        try:
            import sb3_contrib  # noqa: F401
            import stable_baselines3  # noqa: F401
        except ImportError:
            raise LedsimError("the RL baseline needs stable-baselines3 and sb3-contrib: "
                              "pip install 'ledsim[rl,train]'") from None
    except LedsimError as exc:
        print(f"rl_baseline: error: {exc}", file=sys.stderr)
        return 2

    dist = tuple(args.disturbance)
    results, curves = {}, {}
    scratch = tempfile.mkdtemp(prefix="rl_baseline_")
    for name in ("ppo", "recurrent_ppo"):
        model, seconds, curves[name] = train(name, args.steps, dist,
                                             vector_envs=args.vector_envs)
        scores = evaluate(model_policy(model, name == "recurrent_ppo"), dist, args.seeds,
                          stack=8 if name == "ppo" else 1)
        results[name] = dict(**scores, train_seconds=seconds, env_steps=args.steps)
        model.save(Path(scratch) / f"{name}.zip")  # moved in beside results.json below
        print(name, {k: v for k, v in results[name].items() if k != "starts"}, flush=True)
    results.update(references(dist, args.seeds))
    with output_folder(out) as tmp:
        for name in ("ppo", "recurrent_ppo"):
            shutil.move(str(Path(scratch) / f"{name}.zip"), tmp / f"{name}.zip")
        atomic_write_text(tmp / "results.json", json.dumps(
            {"disturbances": list(dist), "steps": args.steps, "eval_seeds": args.seeds,
             "vector_envs": args.vector_envs, **results}, indent=2) + "\n")
        _plot(curves, tmp / "learning_curve.png")
    return 0


def references(dist: tuple, seeds: int) -> dict:
    """The shipped stack's and the oracle's scores as policies of the same env, with
    the default acquisition (``shipped_kkl``, ``oracle``) and with each one named."""
    from ledsim.envs import ShippedAlignmentPolicy
    from ledsim.loop.run_config import TaskPart

    results = {}
    for name, estimator in (("shipped_kkl", "kkl"), ("oracle", "oracle")):
        for acq in ("warm-up", "minimum-time"):
            scores = evaluate(
                lambda env, e=estimator: ShippedAlignmentPolicy(env.unwrapped, e), dist,
                seeds, acquisition=acq)
            row = dict(**scores, train_seconds=0.0, env_steps=0, acquisition=acq)
            results[f"{name}_{acq.replace('-', '_')}"] = row
            if acq == TaskPart.acquisition:
                results[name] = row
            print(name, acq, {k: v for k, v in row.items() if k != "starts"}, flush=True)
    return results


def reference_only(out: Path, seeds: int) -> int:
    """``--reference-only``: the reference rows of ``out/results.json`` again."""
    path = out / "results.json"
    try:
        saved = json.loads(path.read_text())
        dist = tuple(saved["disturbances"])
    except (OSError, ValueError, KeyError):
        print(f"rl_baseline: error: --reference-only needs a results.json of an earlier "
              f"run in {str(out)!r}", file=sys.stderr)
        return 2
    saved.update(references(dist, saved.get("eval_seeds", seeds)))
    atomic_write_text(path, json.dumps(saved, indent=2) + "\n")
    return 0


def _plot(curves: dict, path: Path) -> None:
    from matplotlib.figure import Figure

    from ledsim.files.outputs import atomic_write_bytes

    fig = Figure(figsize=(7, 4))
    ax = fig.add_subplot()
    for name, pts in curves.items():
        if pts:
            x, y = np.array(pts).T
            ax.plot(x, y, ".", alpha=0.3, label=f"{name} (episodes)")
            k = max(1, len(y) // 20)
            ax.plot(x[k - 1:], np.convolve(y, np.ones(k) / k, mode="valid"), "-",
                    label=f"{name} (running mean)")
    ax.axhline(1000, color="grey", lw=0.8, ls=":")
    ax.set(xlabel="environment steps", ylabel="episode return (max 1000)",
           title="LinkAlign-v0: training episodes")
    ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_write_bytes(path, lambda tmp: fig.savefig(tmp, format="png", dpi=100))


if __name__ == "__main__":
    sys.exit(main())
