"""The loop closed in physics: one run of :class:`ClosedLoop`.

MuJoCo supplies the true angle, the ray sensor the two powers, the dropout gate marks
occluded samples missing, an estimator (KKL, EKF, UKF, PF, or the oracle that is handed
the true state) turns them into x_hat, and the scenario's control law torques the gimbal.
Every run of a seed sees the same sensor-noise draws and disturbances whatever the
estimator.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..control import intensity_maximum
from ..optics import peak_power, receiver_response, transmitter_gain
from ..physics.disturbances import parse_disturbance
from ..physics.sensor import IrradianceSensor, SensorReading
from ..physics.simulation import simulate
from ..physics.system import GimbalSystem
from ..physics.world import LinkWorld
from ..results import DictAccess
from .config import RunConfig
from .estimation import (  # noqa: F401 (re-exported)
    check_checkpoint,
    identified_model,
    loop_checkpoint,
    loop_estimator,
)
from .gate import DropoutGate
from .metrics import RunMetrics, run_metrics
from .supervisor import LinkSupervisor

#: Encoder hold during the warm-up: PD on the gimbal angle, 10 rad/s bandwidth,
#: gains in units of the hinge inertia (1/s^2, 1/s).
HOLD_GAINS = (100.0, 20.0)


@dataclass
class Trace(DictAccess):
    """Time series of one run, one row per control step.

    Attributes:
        t [s]; x, xhat: true and estimated (phi [rad], phidot [rad/s]); power,
        power_clean (N, 2) [W]; torque [N m]; occluded (N, 2): any aperture ray blocked;
        lost (N,): the supervisor did not trust the estimate; acquiring (N,): its
        acquisition scan had the motor.
    """

    t: np.ndarray
    x: np.ndarray
    xhat: np.ndarray
    power: np.ndarray
    power_clean: np.ndarray
    torque: np.ndarray
    occluded: np.ndarray
    lost: np.ndarray | None = None
    acquiring: np.ndarray | None = None


@dataclass
class RunOutcome(DictAccess):
    """One seed: its metrics, the estimator's cost [us per step], the loop's real-time
    factor [-], and the trace when asked for."""

    metrics: RunMetrics
    us_per_step: float
    realtime_factor: float
    trace: Trace | None = None


def achievable_power(res, c) -> np.ndarray:
    """Most photodiode 1 could receive at each step of ``res`` [W]: the transmitter gain
    of that moment's distance and LED angle, times the receiver's peak response."""
    g_max = float(receiver_response(intensity_maximum(c), c.receiver))
    return transmitter_gain(res.distance[:, 0], res.emission_angle[:, 0], c) * g_max


def start_world(cfg: RunConfig, system: GimbalSystem, world: LinkWorld, seed: int
                ) -> tuple[IrradianceSensor, list]:
    """Put ``world`` in the scenario's initial state and give it the run's sensor and
    disturbances, both seeded with ``seed``."""
    x0 = cfg.scenario_spec.x0
    world.reset(gimbal_angle=system.phi_home - x0[0], gimbal_rate=0.0 - x0[1])
    sensor = IrradianceSensor(world, seed=seed, noise_scale=cfg.noise_scale)
    disturbances = [parse_disturbance(d) for d in cfg.disturbances]
    for d in disturbances:
        d.reset(seed)
    return sensor, disturbances


def make_supervisor(cfg: RunConfig, system: GimbalSystem, estimator, estimator_system,
                    reacquire: bool) -> LinkSupervisor:
    """The supervisor of one run: its gain prior is the configured distance's over the
    estimator model's, and its noise prior the noise in the model's gain (for a bank)."""
    prior = peak_power(system.constants) / peak_power(estimator_system.constants)
    return LinkSupervisor(estimator, system.constants, system.inertia,
                          warmup=cfg.scenario_spec.warmup, reacquire=reacquire,
                          gain_ratio=prior, noise_ratio=cfg.noise_scale / prior)


def hold_torque(inertia: float, q, qdot, q_hold) -> float | np.ndarray:
    """Motor torque [N m] of the warm-up: while the estimator converges, the motor only
    holds its own encoder angle ``q_hold`` [rad] (PD, :data:`HOLD_GAINS`)."""
    return -HOLD_GAINS[0] * inertia * (q - q_hold) - HOLD_GAINS[1] * inertia * qdot


def outcome(res, xhat: np.ndarray, flags: np.ndarray, cfg: RunConfig, constants,
            disturbances, supervised: bool, spent: float, wall: float,
            keep_trace: bool) -> RunOutcome:
    """A run's :class:`RunOutcome` from its simulation result, its estimates, its
    (lost, acquiring) flags per step, and the seconds spent controlling and in all."""
    events = [d for d in disturbances if d.event_end is not None]
    flags = flags.reshape(-1, 2)
    metrics = run_metrics(res.x, xhat, res.power_clean, cfg.scenario_spec.steady_from,
                          constants, events[0].event_end if events else None,
                          lost=flags[:, 0] if supervised else None,
                          event_start=events[0].start if events else None,
                          power_max=achievable_power(res, constants))
    trace = Trace(res.t, res.x, xhat, res.power, res.power_clean, res.torque,
                  res.occluded, flags[:, 0], flags[:, 1]) if keep_trace else None
    return RunOutcome(metrics, 1e6 * spent / len(res.t),
                      res.t[-1] / wall if len(res.t) else 0.0, trace)


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
        self.estimator, self.estimator_system = loop_estimator(cfg, self.system, self.model)
        if self.estimator is not None:
            self.estimator.seed_run(seed)
        constants = self.system.constants
        self.law = self.scenario.start_law(constants)
        self.gate = DropoutGate(constants)
        self.world = self.system.world
        self.sensor, self.disturbances = start_world(cfg, self.system, self.world, seed)
        if self.estimator is not None:
            self.estimator.reset()
        self.on_step = on_step
        self.q_hold = self.world.gimbal_angle
        self.supervisor = None
        if self.estimator is not None and cfg.supervision:
            self.supervisor = make_supervisor(cfg, self.system, self.estimator,
                                              self.estimator_system, self.law.tracks_beam)
        self.xhats: list[np.ndarray] = []
        self.flags: list[tuple[bool, bool]] = []  # (lost, acquiring) per step
        self.spent = 0.0  # s in the estimator and the law

    def control(self, reading: SensorReading, t: float) -> float:
        """Motor torque [N m] for step t [s] from the sensor reading."""
        t0 = time.perf_counter()
        est, w = self.estimator, self.world
        scan_torque = None
        if est is None:
            xhat = np.array([reading.phi, reading.phidot])
            self.flags.append((False, False))
        else:
            y = self.gate(reading.power)
            if self.supervisor is None:
                xhat = est.update(y)
                self.flags.append((False, False))
            else:
                d = self.supervisor.step(t, y, w.gimbal_angle, w.gimbal_rate)
                xhat, scan_torque = d.xhat, d.torque
                if d.reseeded:
                    self.law = self.scenario.start_law(self.system.constants)
                self.flags.append((d.lost, d.acquiring))
        warming_up = t < self.scenario.warmup
        if scan_torque is not None:
            u = -scan_torque / self.system.inertia
        else:
            u = 0.0 if warming_up else self.law(xhat, t)
        if est is not None:
            est.predict(u)
        self.spent += time.perf_counter() - t0
        self.xhats.append(xhat)
        if self.on_step is not None:
            self.on_step(t, w, reading, xhat)
        if scan_torque is not None:
            return scan_torque
        if warming_up:
            return hold_torque(self.system.inertia, w.gimbal_angle, w.gimbal_rate,
                               self.q_hold)
        return float(self.system.torque_for(u))

    def run(self, keep_trace: bool = False, progress: bool = False) -> RunOutcome:
        t0 = time.perf_counter()
        res = simulate(self.world, self.sensor, self.cfg.run_seconds,
                       disturbances=self.disturbances, controller=self.control,
                       progress=progress)
        wall = time.perf_counter() - t0
        return outcome(res, np.array(self.xhats), np.array(self.flags, dtype=bool),
                       self.cfg, self.system.constants, self.disturbances,
                       self.supervisor is not None, self.spent, wall, keep_trace)


def run_once(cfg: RunConfig, seed: int, keep_trace: bool = False, on_step=None,
             progress: bool = False) -> RunOutcome:
    """One closed-loop run (see :class:`ClosedLoop`)."""
    return ClosedLoop(cfg, seed, on_step).run(keep_trace, progress)
