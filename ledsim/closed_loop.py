"""``ledsim run``: the loop closed in physics.

MuJoCo supplies the true angle, the ray sensor the two powers, an estimator (KKL, EKF,
UKF, PF, or the oracle that is handed the true state) turns them into x_hat, and a
controller torques the gimbal. Every run of a seed sees the same sensor-noise draws
and disturbances whatever the estimator.

==================  ==========================================================
scenario            what happens
==================  ==========================================================
align               start misaligned (phi0 = 0.3 rad); PID control to the peak
open-loop           start at phi0 = 0.3 rad; no input
if1, if2            start aligned; the paper's input functions as u [rad/s^2]
paper-closed-loop   start at 0.2 rad; the paper's u = -0.001 phidot_hat
==================  ==========================================================
"""

from __future__ import annotations

import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from observer import checkpoint
from observer.baselines import ExtendedKalmanFilter, ParticleFilter, UnscentedKalmanFilter
from observer.metrics import mean_and_spread, rmse

from .config import LinkConstants
from .control import AlignmentPID, DropoutGate, Excitation, PaperRateDamping, intensity_maximum
from .disturbances import DisturbanceError, parse_disturbance
from .errors import UserError
from .optics import peak_power
from .physics_system import GimbalSystem, IdentifiedGimbalModel
from .sensor import IrradianceSensor
from .simulation import simulate
from .world import ASSETS, WorldConfig

ESTIMATORS = ("kkl", "ekf", "ukf", "pf", "oracle")
ALIGN_TOLERANCE = math.radians(1.0)  # |phi - phi_ref| below this counts as aligned
AVAILABILITY_LEVEL = 0.9  # link is available while P1 >= 90% of its maximum


@dataclass(frozen=True)
class PhysicsScenario:
    name: str
    phi0: float = 0.3
    seconds: float = 10.0
    law: str = "pd"  # pd, none, if1, if2, paper
    steady_from: float = 5.0  # s: start of the steady-state window


PHYSICS_SCENARIOS = {
    "align": PhysicsScenario("align"),
    "open-loop": PhysicsScenario("open-loop", law="none"),
    "if1": PhysicsScenario("if1", phi0=0.0, law="if1"),
    "if2": PhysicsScenario("if2", phi0=0.0, law="if2"),
    "paper-closed-loop": PhysicsScenario("paper-closed-loop", phi0=0.2, law="paper"),
}


def physics_checkpoint(distance: float) -> Path:
    return ASSETS / "checkpoints" / f"kkl_mujoco_d{distance:g}.pt"


@dataclass
class RunConfig:
    """Everything one ``ledsim run`` needs (all plain data, so it pickles to workers)."""

    scenario: str = "align"
    estimator: str = "kkl"
    disturbances: tuple[str, ...] = ()
    distance: float = 0.085
    torque_limit: float = 0.05
    noise_scale: float = 1.0
    seeds: int = 4
    particles: int = 2000
    checkpoint: str | None = None
    omega_model: str = "identified"  # f for the KKL's Omega: identified | simulator | none
    workers: int = 2
    extra: dict = field(default_factory=dict)

    def validate(self) -> None:
        if self.scenario not in PHYSICS_SCENARIOS:
            raise UserError(f"unknown scenario {self.scenario!r}: choose one of "
                            f"{', '.join(PHYSICS_SCENARIOS)}")
        if self.estimator not in ESTIMATORS:
            raise UserError(f"unknown estimator {self.estimator!r}: choose one of "
                            f"{', '.join(ESTIMATORS)}")
        if not self.distance > 0:
            raise UserError(f"--distance {self.distance!r} is not allowed: must be > 0 m")
        if not self.torque_limit > 0:
            raise UserError(f"--torque-limit {self.torque_limit!r} is not allowed: "
                            "must be > 0 N m")
        if self.seeds < 1:
            raise UserError(f"--seeds {self.seeds!r} is not allowed: must be >= 1")
        if not self.noise_scale > 0:
            raise UserError(f"--noise-scale {self.noise_scale!r} is not allowed: must be > 0")
        if self.omega_model not in ("identified", "simulator", "none"):
            raise UserError(f"--omega-model {self.omega_model!r}: use identified, simulator "
                            "or none")
        try:
            for d in self.disturbances:
                parse_disturbance(d)
        except DisturbanceError as exc:
            raise UserError(str(exc)) from None

    def world_config(self) -> WorldConfig:
        return WorldConfig(constants=LinkConstants(distance=self.distance),
                           torque_limit=self.torque_limit)


def build_estimator(cfg: RunConfig, system: GimbalSystem, model: IdentifiedGimbalModel):
    """The estimator named in ``cfg``, working through ``model`` (None for the oracle)."""
    if cfg.estimator == "oracle":
        return None
    if cfg.estimator == "kkl":
        path = Path(cfg.checkpoint) if cfg.checkpoint else physics_checkpoint(cfg.distance)
        if not path.is_file() and not cfg.checkpoint:
            raise UserError(f"no shipped MuJoCo observer for distance {cfg.distance:g} m: "
                            "train one with `python scripts/train_mujoco.py --distance "
                            f"{cfg.distance:g}` and pass --checkpoint")
        try:
            obs = checkpoint.load(path, system)
        except checkpoint.CheckpointError as exc:
            raise UserError(str(exc)) from None
        if cfg.omega_model == "identified":
            obs.system = model
        elif cfg.omega_model == "simulator":
            # Its own copy of the world: f() resets MuJoCo's state to evaluate a step.
            obs.system = GimbalSystem(cfg.world_config())
        obs.omega = cfg.omega_model != "none"
        return obs
    if cfg.estimator == "ekf":
        return ExtendedKalmanFilter(model)
    if cfg.estimator == "ukf":
        return UnscentedKalmanFilter(model)
    return ParticleFilter(model, cfg.particles)


_MODELS: dict = {}


def identified_model(system: GimbalSystem) -> IdentifiedGimbalModel:
    """The fitted one-step model of this world (cached per process and world)."""
    key = json.dumps(system.metadata(), sort_keys=True)
    if key not in _MODELS:
        _MODELS[key] = IdentifiedGimbalModel.fit(system)
    return _MODELS[key]


def control_law(scenario: PhysicsScenario, constants: LinkConstants):
    if scenario.law == "pd":
        return AlignmentPID(phi_ref=intensity_maximum(constants), Te=constants.Te)
    if scenario.law == "paper":
        return PaperRateDamping()
    if scenario.law == "if1":
        return Excitation(cos_amp=0.1)
    if scenario.law == "if2":
        return Excitation(cos_amp=0.1, sin_amp=0.2)
    return Excitation()


def run_once(cfg: RunConfig, seed: int, keep_trace: bool = False, on_step=None,
             progress: bool = False) -> dict:
    """One closed-loop run; returns metrics (and the time series if ``keep_trace``).

    ``on_step(t, world, reading, xhat)`` is called at every control step before physics
    advances (the renderer uses it).
    """
    scenario = PHYSICS_SCENARIOS[cfg.scenario]
    system = GimbalSystem(cfg.world_config())
    model = identified_model(system)
    est = build_estimator(cfg, system, model)
    if isinstance(est, ParticleFilter):
        est.seed = 10_000 + seed
    constants = system.constants
    law = control_law(scenario, constants)
    gate = DropoutGate(constants)
    world = system.world
    world.reset(gimbal_angle=system.phi_home - scenario.phi0)
    sensor = IrradianceSensor(world, seed=seed, noise_scale=cfg.noise_scale)
    disturbances = [parse_disturbance(d) for d in cfg.disturbances]
    for d in disturbances:
        if hasattr(d, "seed"):
            d.seed = seed
            d.__post_init__()
    xhats, spent = [], [0.0]
    if est is not None:
        est.reset()

    q_hold = world.gimbal_angle
    warmup = getattr(law, "warmup", 0.0)
    brake = (system.inertia * 100.0, system.inertia * 20.0)  # encoder PD, 10 rad/s

    def controller(reading, t):
        t0 = time.perf_counter()
        if est is None:
            xhat = np.array([reading.phi, reading.phidot])
        else:
            xhat = est.update(gate(reading.power))
        u = law(xhat, t)
        if est is not None:
            est.predict(u)
        spent[0] += time.perf_counter() - t0
        xhats.append(xhat)
        if on_step is not None:
            on_step(t, world, reading, xhat)
        if t < warmup:
            # While the estimator converges, the motor only holds its own encoder angle.
            return -brake[0] * (world.gimbal_angle - q_hold) - brake[1] * world.gimbal_rate
        return float(system.torque_for(u))

    t0 = time.perf_counter()
    res = simulate(world, sensor, cfg.extra.get("seconds", scenario.seconds),
                   disturbances=disturbances, controller=controller, progress=progress)
    wall = time.perf_counter() - t0
    xhat = np.array(xhats)
    return {"metrics": metrics(res, xhat, scenario, constants, disturbances),
            "us_per_step": 1e6 * spent[0] / len(res.t),
            "realtime_factor": res.t[-1] / wall if len(res.t) else 0.0,
            "trace": {"t": res.t, "x": res.x, "xhat": xhat, "power": res.power,
                      "power_clean": res.power_clean, "torque": res.torque,
                      "occluded": res.occluded} if keep_trace else None}


def metrics(res, xhat, scenario, constants, disturbances) -> dict:
    """RMSE, alignment time, link availability, mean power and occlusion recovery."""
    Te = constants.Te
    start = int(round(scenario.steady_from / Te))
    e = rmse(xhat, res.x)
    es = rmse(xhat, res.x, start)
    phi_ref = intensity_maximum(constants)
    aligned = np.abs(res.phi - phi_ref) < ALIGN_TOLERANCE
    p_max = peak_power(constants)
    p1 = res.power_clean[:, 0]
    out = {"rmse": {"x1": float(e[0]), "x2": float(e[1])},
           "rmse_steady": {"x1": float(es[0]), "x2": float(es[1])},
           "alignment_time": first_settled(aligned, Te),
           "availability": float(np.mean(p1 >= AVAILABILITY_LEVEL * p_max)),
           "mean_power": float(np.mean(p1)),
           "recovery_time": None}
    occ = [d for d in disturbances if type(d).__name__ == "Occlusion"]
    if occ:
        end = int(round((occ[0].start + occ[0].duration) / Te))
        rec = first_settled(aligned[end:], Te)
        out["recovery_time"] = rec
    return out


def first_settled(flags: np.ndarray, Te: float, hold: float = 0.5) -> float | None:
    """First time [s] from which ``flags`` stays true for ``hold`` s (None: never)."""
    n_hold = int(round(hold / Te))
    ok = np.asarray(flags, dtype=bool)
    if len(ok) < n_hold:
        return None
    run = np.convolve(ok.astype(int), np.ones(n_hold, dtype=int), mode="valid")
    idx = np.flatnonzero(run == n_hold)
    return None if idx.size == 0 else float(idx[0] * Te)


def _job(args):
    cfg, seed, keep = args
    return run_once(cfg, seed, keep)


def run_many(cfg: RunConfig, progress: bool = True) -> tuple[dict, dict | None]:
    """Monte-Carlo over seeds on ``cfg.workers`` processes; returns (summary, trace 0)."""
    cfg.validate()
    # Fail fast on a bad checkpoint or world before spawning workers.
    if cfg.estimator == "kkl":
        system = GimbalSystem(cfg.world_config())
        build_estimator(cfg, system, system)
    jobs = [(cfg, seed, seed == 0) for seed in range(cfg.seeds)]
    if cfg.workers > 1 and cfg.seeds > 1:
        with ProcessPoolExecutor(min(cfg.workers, cfg.seeds)) as pool:
            outs = list(tqdm(pool.map(_job, jobs), total=len(jobs), disable=not progress,
                             desc=f"{cfg.scenario}/{cfg.estimator}", leave=False))
    else:
        outs = [_job(j) for j in tqdm(jobs, disable=not progress, leave=False,
                                      desc=f"{cfg.scenario}/{cfg.estimator}")]
    return summarize(cfg, outs), outs[0]["trace"]


def summarize(cfg: RunConfig, outs: list[dict]) -> dict:
    def stat(get):
        vals = [get(o) for o in outs]
        vals = [v for v in vals if v is not None]
        if not vals:
            return {"mean": None, "std": None, "n": 0}
        mean, spread = mean_and_spread(np.array(vals, dtype=float))
        return {"mean": float(mean), "std": float(spread), "n": len(vals)}

    m = lambda o: o["metrics"]  # noqa: E731
    return {
        "scenario": cfg.scenario, "estimator": cfg.estimator,
        "disturbances": list(cfg.disturbances), "distance": cfg.distance,
        "noise_scale": cfg.noise_scale, "seeds": cfg.seeds, "omega_model": cfg.omega_model,
        "rmse_x1": stat(lambda o: m(o)["rmse"]["x1"]),
        "rmse_x2": stat(lambda o: m(o)["rmse"]["x2"]),
        "rmse_steady_x1": stat(lambda o: m(o)["rmse_steady"]["x1"]),
        "rmse_steady_x2": stat(lambda o: m(o)["rmse_steady"]["x2"]),
        "alignment_time": stat(lambda o: m(o)["alignment_time"]),
        "aligned_runs": sum(m(o)["alignment_time"] is not None for o in outs),
        "availability": stat(lambda o: m(o)["availability"]),
        "mean_power": stat(lambda o: m(o)["mean_power"]),
        "recovery_time": stat(lambda o: m(o)["recovery_time"]),
        "us_per_step": stat(lambda o: o["us_per_step"]),
        "realtime_factor": stat(lambda o: o["realtime_factor"]),
    }


def plot_trace(trace: dict, summary: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = trace["t"]
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for i, (ax, label) in enumerate(zip(axes[:2], ["phi [rad]", "phidot [rad/s]"],
                                        strict=True)):
        ax.plot(t, trace["x"][:, i], "k", lw=2, label="MuJoCo truth")
        ax.plot(t, trace["xhat"][:, i], "C0", lw=1, label=f"{summary['estimator']} estimate")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    ax = axes[2]
    for j in range(2):
        ax.plot(t, trace["power"][:, j], lw=0.5, alpha=0.5, color=f"C{j}")
        ax.plot(t, trace["power_clean"][:, j], lw=1.5, color=f"C{j}", label=f"P{j + 1}")
    occ = trace["occluded"].any(axis=1)
    if occ.any():
        ax.fill_between(t, 0, 1, where=occ, transform=ax.get_xaxis_transform(), color="k",
                        alpha=0.12, label="blocked")
    ax.set_ylabel("power [W]")
    ax.set_xlabel("time [s]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    dist = ", ".join(summary["disturbances"]) or "no disturbance"
    axes[0].set_title(f"{summary['scenario']} with {summary['estimator']} — {dist}")
    fig.tight_layout()
    checkpoint.atomic_write_bytes(Path(path), lambda tmp: fig.savefig(tmp, dpi=110,
                                                                      format="png"))
    plt.close(fig)


def write_run(summary: dict, trace: dict | None, out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "results.json"]
    checkpoint.atomic_write_text(paths[0], json.dumps(summary, indent=2) + "\n")
    if trace is not None:
        paths.append(out / "run.png")
        plot_trace(trace, summary, paths[-1])
    return paths


def format_summary(s: dict) -> str:
    def f(key, fmt="{:.2e}"):
        v = s[key]["mean"]
        return "-" if v is None else fmt.format(v)

    return (f"| {s['scenario']} | {', '.join(s['disturbances']) or '-'} | {s['estimator']} "
            f"| {f('rmse_steady_x1')} | {f('rmse_steady_x2')} | {f('alignment_time', '{:.2f}')} "
            f"| {f('availability', '{:.3f}')} | {f('mean_power', '{:.3f}')} "
            f"| {f('recovery_time', '{:.2f}')} | {f('realtime_factor', '{:.0f}')} |")


TABLE_HEADER = ("| scenario | disturbance | estimator | x1 RMSE [rad] | x2 RMSE [rad/s] "
                "| align time [s] | availability | mean P1 [W] | recovery [s] | RTF |\n"
                "|---|---|---|---|---|---|---|---|---|---|")
