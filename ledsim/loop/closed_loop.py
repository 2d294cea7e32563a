"""The loop closed in physics: one run of :class:`ClosedLoop`.

MuJoCo supplies the true angle, the ray sensor the two powers, the dropout gate marks
occluded samples missing, an estimator (KKL, EKF, UKF, PF, or the oracle that is handed
the true state) turns them into x_hat, and the scenario's control law torques the gimbal.
Every run of a seed sees the same sensor-noise draws and disturbances whatever the
estimator.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from observer import checkpoint as ckpt

from ..estimators import build_estimator
from ..physics.disturbances import parse_disturbance
from ..physics.sensor import IrradianceSensor, SensorReading
from ..physics.simulation import simulate
from ..physics.system import GimbalSystem, IdentifiedGimbalModel
from ..resources import require_shipped_checkpoint
from ..results import DictAccess
from .config import RunConfig
from .gate import DropoutGate
from .metrics import RunMetrics, run_metrics

#: Encoder hold during the warm-up: PD on the gimbal angle, 10 rad/s bandwidth,
#: gains in units of the hinge inertia (1/s^2, 1/s).
HOLD_GAINS = (100.0, 20.0)


@dataclass
class Trace(DictAccess):
    """Time series of one run, one row per control step.

    Attributes:
        t [s]; x, xhat: true and estimated (phi [rad], phidot [rad/s]); power,
        power_clean (N, 2) [W]; torque [N m]; occluded (N, 2): any aperture ray blocked.
    """

    t: np.ndarray
    x: np.ndarray
    xhat: np.ndarray
    power: np.ndarray
    power_clean: np.ndarray
    torque: np.ndarray
    occluded: np.ndarray


@dataclass
class RunOutcome(DictAccess):
    """One seed: its metrics, the estimator's cost [us per step], the loop's real-time
    factor [-], and the trace when asked for."""

    metrics: RunMetrics
    us_per_step: float
    realtime_factor: float
    trace: Trace | None = None


_MODELS: dict = {}


def identified_model(system: GimbalSystem) -> IdentifiedGimbalModel:
    """The fitted one-step model of this world (cached per process and world)."""
    key = json.dumps(system.metadata(), sort_keys=True)
    if key not in _MODELS:
        _MODELS[key] = IdentifiedGimbalModel.fit(system)
    return _MODELS[key]


def loop_checkpoint(cfg: RunConfig):
    """The KKL checkpoint of a run: ``cfg.checkpoint`` or the shipped MuJoCo observer."""
    return cfg.checkpoint or require_shipped_checkpoint(cfg.distance, "mujoco")


def check_checkpoint(cfg: RunConfig) -> None:
    """Fail fast (before any worker starts) on a checkpoint that does not fit the world."""
    if cfg.estimator == "kkl":
        ckpt.load(loop_checkpoint(cfg), GimbalSystem(cfg.world_config()))


class ClosedLoop:
    """One closed-loop run of ``cfg`` with seed ``seed``.

    Args:
        cfg: the run.
        seed: seeds the sensor noise, the disturbances and the particle filter.
        on_step: ``on_step(t, world, reading, xhat)`` at every control step before physics
            advances (the renderer uses it).
    """

    def __init__(self, cfg: RunConfig, seed: int,
                 on_step: Callable[..., None] | None = None):
        self.cfg = cfg
        self.scenario = cfg.scenario_spec
        self.system = GimbalSystem(cfg.world_config())
        self.model = identified_model(self.system)
        self.estimator = self._estimator()
        if self.estimator is not None:
            self.estimator.seed_run(seed)
        constants = self.system.constants
        self.law = self.scenario.start_law(constants)
        self.gate = DropoutGate(constants)
        self.world = self.system.world
        self.world.reset(gimbal_angle=self.system.phi_home - self.scenario.x0[0],
                         gimbal_rate=0.0 - self.scenario.x0[1])
        self.sensor = IrradianceSensor(self.world, seed=seed, noise_scale=cfg.noise_scale)
        self.disturbances = [parse_disturbance(d) for d in cfg.disturbances]
        for d in self.disturbances:
            d.reset(seed)
        if self.estimator is not None:
            self.estimator.reset()
        self.on_step = on_step
        self.q_hold = self.world.gimbal_angle
        self.xhats: list[np.ndarray] = []
        self.spent = 0.0  # s in the estimator and the law

    def _estimator(self):
        cfg = self.cfg
        if cfg.estimator != "kkl":
            return build_estimator(cfg.estimator, self.system, model=self.model,
                                   particles=cfg.particles)
        # Omega's f: the identified model; or the simulator in a world of its own, since
        # f() resets MuJoCo's state to evaluate a step; or none.
        if cfg.omega_model == "simulator":
            omega_f = GimbalSystem(cfg.world_config())
        else:
            omega_f = self.model if cfg.omega_model == "identified" else self.system
        return build_estimator("kkl", self.system, model=omega_f,
                               checkpoint=loop_checkpoint(cfg),
                               omega=cfg.omega_model != "none")

    def control(self, reading: SensorReading, t: float) -> float:
        """Motor torque [N m] for step t [s] from the sensor reading."""
        t0 = time.perf_counter()
        est = self.estimator
        if est is None:
            xhat = np.array([reading.phi, reading.phidot])
        else:
            xhat = est.update(self.gate(reading.power))
        warming_up = t < self.scenario.warmup
        u = 0.0 if warming_up else self.law(xhat, t)
        if est is not None:
            est.predict(u)
        self.spent += time.perf_counter() - t0
        self.xhats.append(xhat)
        if self.on_step is not None:
            self.on_step(t, self.world, reading, xhat)
        if warming_up:
            # While the estimator converges, the motor only holds its own encoder angle.
            w, inertia = self.world, self.system.inertia
            return (-HOLD_GAINS[0] * inertia * (w.gimbal_angle - self.q_hold)
                    - HOLD_GAINS[1] * inertia * w.gimbal_rate)
        return float(self.system.torque_for(u))

    def run(self, keep_trace: bool = False, progress: bool = False) -> RunOutcome:
        t0 = time.perf_counter()
        res = simulate(self.world, self.sensor, self.cfg.run_seconds,
                       disturbances=self.disturbances, controller=self.control,
                       progress=progress)
        wall = time.perf_counter() - t0
        xhat = np.array(self.xhats)
        ends = [d.event_end for d in self.disturbances if d.event_end is not None]
        metrics = run_metrics(res.x, xhat, res.power_clean, self.scenario.steady_from,
                              self.system.constants, ends[0] if ends else None)
        trace = Trace(res.t, res.x, xhat, res.power, res.power_clean, res.torque,
                      res.occluded) if keep_trace else None
        return RunOutcome(metrics, 1e6 * self.spent / len(res.t),
                          res.t[-1] / wall if len(res.t) else 0.0, trace)


def run_once(cfg: RunConfig, seed: int, keep_trace: bool = False, on_step=None,
             progress: bool = False) -> RunOutcome:
    """One closed-loop run (see :class:`ClosedLoop`)."""
    return ClosedLoop(cfg, seed, on_step).run(keep_trace, progress)
