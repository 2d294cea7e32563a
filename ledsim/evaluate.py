"""``ledsim evaluate``: the paper's Table 1/2 experiments with KKL and the baselines.

Every estimator sees exactly the same noise draws per seed (open-loop scenarios: the
same measurement sequences). Monte-Carlo runs are spread over worker processes.
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from observer import checkpoint
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
from observer.estimator import Estimator
from observer.metrics import converged, mean_and_spread, rmse

from .config import LinkConstants
from .errors import UserError
from .paper_model import LEDLinkModel
from .scenarios import PAPER_TABLE1, PAPER_TABLE2, Noise, get_scenario, run

ASSETS = Path(__file__).resolve().parent.parent / "assets"
CHECKPOINT_DIR = ASSETS / "checkpoints"
CONVERGENCE_TOLERANCE = 0.02  # rad: steady-state x1 RMSE below this counts as converged


def default_checkpoint(distance: float, design: str = "default") -> Path:
    """The shipped checkpoint for a link distance (``assets/checkpoints``)."""
    prefix = "kkl_paper" if design == "paper" else "kkl"
    return CHECKPOINT_DIR / f"{prefix}_d{distance:g}.pt"


@dataclass
class EvaluationConfig:
    scenario: str = "open-loop"
    distance: float = 0.085
    dphi: float = LinkConstants().dphi  # rad
    seeds: int = 10
    starts: int = 100  # random initial guesses for the convergence share
    particles: int = 5000
    checkpoint: str | None = None
    workers: int = 2
    estimators: tuple[str, ...] = ("kkl", "kkl-paper", "ekf", "ukf", "pf")

    def validate(self) -> None:
        try:
            get_scenario(self.scenario)
        except KeyError as exc:
            raise UserError(exc.args[0]) from None
        if not self.distance > 0:
            raise UserError(f"--distance {self.distance!r} is not allowed: must be > 0 m")
        if self.dphi == 0:
            raise UserError("--dphi 0 is not allowed: the two photodiodes must point in "
                            "different directions")
        if self.seeds < 1:
            raise UserError(f"--seeds {self.seeds!r} is not allowed: must be >= 1")
        if self.starts < 0:
            raise UserError(f"--starts {self.starts!r} is not allowed: must be >= 0")
        if self.particles < 1:
            raise UserError(f"--particles {self.particles!r} is not allowed: must be >= 1")


def build_estimators(system: LEDLinkModel, cfg: EvaluationConfig) -> dict[str, Estimator]:
    """KKL (from a checkpoint checked against ``system``) and the baselines."""
    ests: dict[str, Estimator] = {}
    for name in cfg.estimators:
        if name == "kkl":
            path = Path(cfg.checkpoint) if cfg.checkpoint else default_checkpoint(
                system.constants.distance)
            if not path.is_file() and not cfg.checkpoint:
                raise UserError(
                    f"no shipped checkpoint for distance {system.constants.distance:g} m: "
                    f"train one with `ledsim train --distance {system.constants.distance:g} "
                    "--out PATH` and pass --checkpoint PATH")
            try:
                ests["kkl"] = checkpoint.load(path, system)
            except checkpoint.CheckpointError as exc:
                raise UserError(str(exc)) from None
        elif name == "kkl-paper":
            path = default_checkpoint(system.constants.distance, "paper")
            if path.is_file() and not cfg.checkpoint:
                obs = checkpoint.load(path, system)
                obs.name = "kkl-paper"
                ests["kkl-paper"] = obs
        elif name == "ekf":
            ests["ekf"] = ExtendedKalmanFilter(system)
        elif name == "ukf":
            ests["ukf"] = UnscentedKalmanFilter(system)
        elif name == "pf":
            ests["pf"] = ParticleFilter(system, cfg.particles)
        else:
            raise UserError(f"unknown estimator {name!r}: choose from kkl, kkl-paper, ekf, "
                            "ukf, pf")
    return ests


def _job(args):
    system, scenario, est, seed, x0_guess, keep = args
    if isinstance(est, ParticleFilter):
        est.seed = 10_000 + seed
    out = run(system, scenario, est, Noise.draw(system, scenario.n_steps, seed), x0_guess)
    s = scenario.steady_from
    metrics = {
        "rmse": np.r_[rmse(out["xhat"], out["x"]), rmse(out["yhat"], out["y_clean"])],
        "rmse_steady": np.r_[rmse(out["xhat"], out["x"], s), rmse(out["yhat"], out["y_clean"], s)],
        "converged": converged(out["xhat"], out["x"], s, CONVERGENCE_TOLERANCE),
        "us_per_step": 1e6 * out["seconds"] / scenario.n_steps,
    }
    return metrics, (out if keep else None)


def _map(jobs, workers, desc):
    if workers <= 1:
        return [_job(j) for j in tqdm(jobs, desc=desc, leave=False)]
    with ProcessPoolExecutor(workers) as pool:
        return list(tqdm(pool.map(_job, jobs, chunksize=1), total=len(jobs), desc=desc,
                         leave=False))


def evaluate(cfg: EvaluationConfig, constants: LinkConstants | None = None) -> tuple[dict, dict]:
    """Run the Monte-Carlo comparison; returns ``(results, traces of seed 0)``."""
    cfg.validate()
    base = constants or LinkConstants()
    try:
        system = LEDLinkModel(base.with_(distance=cfg.distance, dphi=cfg.dphi))
    except ValueError as exc:
        raise UserError(str(exc)) from None
    scenario = get_scenario(cfg.scenario)
    ests = build_estimators(system, cfg)
    rng = np.random.default_rng(12345)
    starts = rng.uniform(system.domain_low, system.domain_high, size=(cfg.starts, 2))
    jobs = []  # per estimator: its seeds, then its random starts
    for est in ests.values():
        jobs += [(system, scenario, est, seed, None, seed == 0) for seed in range(cfg.seeds)]
        jobs += [(system, scenario, est, 1000 + i, starts[i], False) for i in range(cfg.starts)]
    outputs = _map(jobs, cfg.workers, f"{cfg.scenario} d={cfg.distance:g}")
    names = ["x1", "x2", "y1", "y2"]
    results = {"scenario": cfg.scenario, "distance": cfg.distance, "seeds": cfg.seeds,
               "starts": cfg.starts, "n_steps": scenario.n_steps,
               "steady_from": scenario.steady_from, "Te": system.Te, "estimators": {},
               "paper": paper_reference(cfg.scenario, cfg.distance)}
    traces = {}
    i = 0
    for name in ests:
        seed_metrics = [m for m, _ in outputs[i:i + cfg.seeds]]
        trace = outputs[i][1]
        i += cfg.seeds
        start_metrics = [m for m, _ in outputs[i:i + cfg.starts]]
        i += cfg.starts
        entry = {}
        for key in ("rmse", "rmse_steady"):
            mean, spread = mean_and_spread([m[key] for m in seed_metrics])
            entry[key] = dict(zip(names, mean.tolist(), strict=True))
            entry[key + "_std"] = dict(zip(names, spread.tolist(), strict=True))
        entry["converged_fraction"] = (float(np.mean([m["converged"] for m in start_metrics]))
                                       if start_metrics else None)
        entry["us_per_step"] = float(np.median([m["us_per_step"] for m in seed_metrics]))
        results["estimators"][name] = entry
        traces[name] = trace
    return results, traces


def paper_reference(scenario: str, distance: float) -> dict | None:
    """The paper's RMSE for this case: Table 1 at d0 = 0.085 m, else Table 2, else None."""
    if np.isclose(distance, 0.085) and scenario in PAPER_TABLE1:
        row, source = PAPER_TABLE1[scenario], "Table 1"
    elif (scenario, distance) in PAPER_TABLE2:
        row, source = PAPER_TABLE2[(scenario, distance)], "Table 2"
    else:
        return None
    return {**dict(zip(["x1", "x2", "y1", "y2"], row, strict=True)), "source": source}


def markdown_table(results: dict) -> str:
    """RMSE table (mean +- std over seeds) beside the paper's value."""
    lines = [f"### {results['scenario']}, d = {results['distance']:g} m, "
             f"{results['seeds']} seeds (steady state from step {results['steady_from']} "
             f"of {results['n_steps']})", "",
             "| estimator | x1 [rad] | x2 [rad/s] | y1 [W] | y2 [W] | x1 whole run [rad] "
             "| converged | us/step |",
             "|---|---|---|---|---|---|---|---|"]
    for name, e in results["estimators"].items():
        cells = [f"{e['rmse_steady'][k]:.2e} ± {e['rmse_steady_std'][k]:.1e}"
                 for k in ("x1", "x2", "y1", "y2")]
        conv = "-" if e["converged_fraction"] is None else f"{100 * e['converged_fraction']:.0f}%"
        lines.append(f"| {name} | " + " | ".join(cells) +
                     f" | {e['rmse']['x1']:.2e} | {conv} | {e['us_per_step']:.1f} |")
    if results["paper"]:
        p = results["paper"]
        lines.append(f"| paper ({p['source']}) | " + " | ".join(f"{p[k]:.2e}" for k in
                                                          ("x1", "x2", "y1", "y2")) +
                     " | | | |")
    return "\n".join(lines) + "\n"


def plot(results: dict, traces: dict, out_dir: Path, Te: float) -> list[Path]:
    """Figures like the paper's Figs 5-11: states and powers, true vs estimated (seed 0)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    kkl = traces.get("kkl") or next(iter(traces.values()))
    t = np.arange(len(kkl["x"])) * Te
    title = f"{results['scenario']}, d = {results['distance']:g} m"
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for i, (ax, label) in enumerate(zip(axes, ["phi [rad]", "phidot [rad/s]"], strict=True)):
        ax.plot(t, kkl["x"][:, i], "k", lw=2, label="true")
        for name, tr in traces.items():
            ax.plot(t, tr["xhat"][:, i], lw=1, alpha=0.9 if name == "kkl" else 0.6, label=name)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(ncol=3, fontsize=8)
    axes[0].set_title(f"true vs estimated state — {title}")
    axes[1].set_xlabel("time [s]")
    fig.tight_layout()
    paths.append(out_dir / "states.png")
    _save_fig(fig, paths[-1])
    plt.close(fig)

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for i, ax in enumerate(axes):
        ax.plot(t, kkl["y"][:, i], color="0.75", lw=0.5, label="measured")
        ax.plot(t, kkl["y_clean"][:, i], "k", lw=2, label="true")
        ax.plot(t, kkl["yhat"][:, i], "C0", lw=1, label="predicted h(x_hat), KKL")
        ax.set_ylabel(f"P{i + 1} [W]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"photodiode powers — {title}")
    axes[1].set_xlabel("time [s]")
    fig.tight_layout()
    paths.append(out_dir / "powers.png")
    _save_fig(fig, paths[-1])
    plt.close(fig)
    return paths


def _save_fig(fig, path: Path) -> None:
    checkpoint.atomic_write_bytes(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"))


def write_outputs(results: dict, traces: dict, out_dir: Path, Te: float) -> list[Path]:
    """results.json, table.md and figures; each written atomically."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = plot(results, traces, out_dir, Te)
    checkpoint.atomic_write_text(out_dir / "table.md", markdown_table(results))
    checkpoint.atomic_write_text(out_dir / "results.json", json.dumps(results, indent=2) + "\n")
    return [out_dir / "results.json", out_dir / "table.md", *paths]
