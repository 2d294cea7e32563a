"""The loop closed in physics: one seed or many, through the one control step.

MuJoCo supplies the true angle, the ray sensors the two powers (every seed's read in
one pass: :class:`~ledsim.physics.sensor_rows.SensorRows`), and each seed's
:class:`~ledsim.agent.step.ControlStep` (dropout gate, supervisor with its estimator, control
law, motor) turns them into a motor torque; :func:`~ledsim.physics.tick.advance` moves
the world on. :class:`ClosedLoop` steps the runs of several seeds together, their
physics split over threads (MuJoCo steps without the GIL); a run of one seed is the
same code with N = 1, so a seed's numbers are the same whatever else runs beside it.
Every run of a seed sees the same sensor-noise draws and disturbances whatever the
estimator.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Sequence

import numpy as np
from tqdm.auto import tqdm

from ledsim.agent.autopilot import Vehicle
from ledsim.agent.gate import DropoutGate
from ledsim.agent.laws import intensity_maximum
from ledsim.agent.slew import TimeOptimalSlew
from ledsim.agent.step import ControlStep, GimbalMotor, Unsupervised
from ledsim.agent.supervisor import LinkSupervisor
from ledsim.experiment.montecarlo import report_progress
from ledsim.loop.build import build_worlds
from ledsim.loop.estimation import (  # noqa: F401 (re-exported)
    check_checkpoint,
    identified_model,
    loop_checkpoint,
    loop_estimator,
    run_noise,
)
from ledsim.loop.given import GivenRecord
from ledsim.loop.outcome import Navigation, RunOutcome, RunRecord, Trace, achievable_power, outcome  # noqa: F401
from ledsim.loop.run_config import RunConfig
from ledsim.loop.start import Surroundings, start_world  # noqa: F401 (re-exported)
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.gimbal_system import GimbalSystem
from ledsim.physics.sensor import SensorReading
from ledsim.physics.sensor_rows import SensorRows
from ledsim.physics.simulation import SimulationResult
from ledsim.physics.tick import PhysicsPass, step_worlds
from ledsim.physics.world import LinkWorld
from ledsim.radiometry.optics import nominal_noise_std, peak_power
from observer.baselines.oracle import Oracle
from observer.noise import MeasurementNoise
from observer.recording import RecordingEstimator

#: Steps between two reports of a run's progress (montecarlo.report_progress).
REPORT_EVERY = 50


def make_supervisor(cfg: RunConfig, system: GimbalSystem, estimator, estimator_system,
                    reacquire: bool, noise: MeasurementNoise) -> LinkSupervisor:
    """The supervisor of one run with measurement noise ``noise``: its gain prior is
    the configured distance's over the estimator model's, and its noise prior the noise
    in the model's gain over the noise that model already carries (for a bank: its
    nominal noise)."""
    prior = peak_power(system.constants) / peak_power(estimator_system.constants)
    carried = (estimator_system.constants.measurement_noise_std
               / nominal_noise_std(system.constants))
    return LinkSupervisor(estimator, system.constants, system.inertia,
                          warmup=cfg.scenario_spec.warmup, reacquire=reacquire,
                          gain_ratio=prior, noise_ratio=noise.scale / prior / carried,
                          dead_reckon=cfg.imu,
                          fast=system.config.torque_limit if cfg.fast_acquisition else None)


def run_supervisor(cfg: RunConfig, system: GimbalSystem, model, seed: int,
                   truth: Callable[[], np.ndarray], reacquire: bool, record: bool = False,
                   noise: MeasurementNoise | None = None):
    """The estimator of seed ``seed`` of ``cfg`` under its supervisor (the oracle, which
    reads ``truth``, and runs without supervision are :class:`Unsupervised`);
    ``reacquire``: the supervisor may scan for a lost beam; ``record``: the estimator
    keeps every call it is given (:class:`~observer.recording.RecordingEstimator`);
    ``noise``: the run's measurement noise (None: :func:`run_noise`)."""
    if cfg.estimator == "oracle":
        if not (reacquire and cfg.fast_acquisition):
            return Unsupervised(Oracle(system, truth))
        slew = TimeOptimalSlew(system.inertia, system.config.torque_limit, system.Te)
        return Unsupervised(Oracle(system, truth), slew, intensity_maximum(system.constants))
    noise = run_noise(cfg, system) if noise is None else noise
    est, est_system = loop_estimator(cfg, system, model, noise)
    if record:
        est = RecordingEstimator(est)
    est.seed_run(seed)
    est.reset()
    if not cfg.supervision:
        return Unsupervised(est)
    return make_supervisor(cfg, system, est, est_system, reacquire, noise)


def control_step(cfg: RunConfig, system: GimbalSystem, model, seed: int, q_hold: float,
                 truth: Callable[[], np.ndarray], record: bool = False,
                 noise: MeasurementNoise | None = None) -> ControlStep:
    """The control step of seed ``seed`` of ``cfg`` (``ledsim run``'s stack): dropout
    gate, the estimator under its supervisor (the oracle reads ``truth``), the
    scenario's law, and the gimbal motor holding ``q_hold`` [rad] during the warm-up;
    ``record``: the estimator keeps what it is given."""
    spec = cfg.scenario_spec
    supervisor = run_supervisor(cfg, system, model, seed, truth, spec.law.tracks_beam,
                                record, noise)
    motor = GimbalMotor(system.inertia, q_hold, limit=system.config.torque_limit)
    return ControlStep(dropout_gate(system.constants, supervisor), supervisor, spec.law,
                       system.constants, motor, spec.warmup, model=model)


def dropout_gate(constants, supervisor) -> DropoutGate:
    """The gate in front of ``supervisor``. Past max_hold it passes a lasting darkness
    on, for a link supervisor to see as a blackout; an estimator alone cannot read
    darkness, so without supervision the gate holds every dark sample."""
    hold = {} if isinstance(supervisor, LinkSupervisor) else {"max_hold": math.inf}
    return DropoutGate(constants, **hold)


class LoopRun:
    """One seed of a closed-loop run: its world, sensor, disturbances, control step, and
    the record of every step (``steps`` rows); with ``record``, also what its estimator
    was given (:mod:`ledsim.loop.given`)."""

    def __init__(self, cfg: RunConfig, seed: int, system: GimbalSystem, model,
                 world: LinkWorld, steps: int, record: bool = False):
        self.seed = seed
        self.world = world
        self.noise = run_noise(cfg, system)
        self.sensor, self.disturbances, self.vehicle = start_world(cfg, system, world, seed,
                                                                   noise=self.noise)
        self.aided = cfg.imu
        self.reading: SensorReading | None = None
        self.step = control_step(cfg, system, model, seed, world.gimbal_angle,
                                 lambda: self.reading.x, record, self.noise)
        self.given = GivenRecord(steps) if record else None
        self.supervised = isinstance(self.step.supervisor, LinkSupervisor)
        lay = system.constants.layout
        npd, nx = lay.n_photodiodes, lay.n_state
        self.geo = np.empty((steps, 4, npd))  # distance, theta, phi, visible fraction
        self.state = np.empty((steps, nx))
        self.gimbal = np.empty((steps, nx))
        self.hull = np.empty((steps, 3))
        self.power = np.empty((steps, npd))
        self.clean = np.empty((steps, npd))
        self.applied = np.empty(steps)
        self.xhat = np.empty((steps, nx))  # what the run reports (held while lost)
        self.own = np.empty((steps, nx))  # the estimator's own estimate
        self.xhat_std = np.full((steps, nx), np.nan)  # the held estimate's std (NaN: none)
        self.flags = np.zeros((steps, 2), dtype=bool)  # lost, acquiring
        self.reseeded = np.zeros(steps, dtype=bool)  # the supervisor restarted the estimator
        # What the estimator was told and given (for the bound): u [rad/s^2], samples.
        self.u = np.zeros(steps)
        self.measured = np.ones((steps, npd), dtype=bool)
        self.outside = np.zeros(steps, dtype=bool)  # the estimator left its training box
        # The medium's factor on the reference photodiode's power (scintillation): the
        # most it could receive fades with it, so a fade is not a pointing loss.
        self.medium = np.ones(steps)
        # The vehicle's navigated position [m] and its station (None: no vehicle).
        self.navigated = np.full((steps, 3), np.nan)
        v = self.vehicle
        self.station = None if v is None else np.r_[v.home[0], v.surface]
        self.spent = 0.0  # s in the control step

    def control(self, k: int, t: float, reading: SensorReading | None = None) -> float:
        """Record the sensor's ``reading`` at step ``k`` (time ``t`` [s]; None: read it
        now), and return the motor torque [N m] the control step commands."""
        r = self.reading = self.sensor.read() if reading is None else reading
        self.geo[k] = r.distance, r.emission_angle, r.incidence_angle, r.visible_fraction
        self.state[k] = r.phi, r.phidot
        self.gimbal[k] = r.gimbal_angle, r.gimbal_rate
        self.hull[k], self.power[k], self.clean[k] = r.hull_pos, r.power, r.power_clean
        if self.world.light_gain is not None:
            self.medium[k] = self.world.light_gain[self.world.config.constants.layout.reference]
        if self.vehicle is not None:
            self.navigated[k] = self.vehicle.navigated_position
        t0 = time.perf_counter()
        los = self.vehicle.los if self.aided else None
        torque = self.step(r.power, t, r.gimbal_angle, r.gimbal_rate, los)
        self.spent += time.perf_counter() - t0
        d = self.step.decision
        self.xhat[k] = d.reported
        self.own[k] = d.xhat
        if d.held_std is not None:
            self.xhat_std[k] = d.held_std
        self.flags[k] = d.lost, d.acquiring
        self.reseeded[k] = d.reseeded
        self.u[k] = self.step.u
        self.measured[k] = np.isfinite(self.step.y_gated)
        self.outside[k] = self.step.supervisor.outside_domain
        if self.given is not None:
            self.given.take(k, self.step, los)
        return torque

    def result(self, times: np.ndarray) -> SimulationResult:
        return SimulationResult.from_steps(times, self.geo, self.state, self.gimbal,
                                           self.applied, self.power, self.clean, self.hull,
                                           self.world.config.constants.layout)


class ClosedLoop:
    """The runs of ``cfg`` for each of ``seeds``, stepped together.

    Args:
        cfg: the configuration (every run's).
        seeds: one run per seed.
        threads: threads stepping the physics (1: the calling thread).
        on_step: ``on_step(run, t)`` after each run's control step, before physics
            advances (the renderer uses it; ``run`` is the seed's :class:`LoopRun`).
        record: keep what each run's estimator is given, for its trace (to replay it).
    """

    def __init__(self, cfg: RunConfig, seeds: Sequence[int] | int = 0, threads: int = 1,
                 on_step: Callable[[LoopRun, float], None] | None = None,
                 record: bool = False):
        seeds = [seeds] if isinstance(seeds, int | np.integer) else list(seeds)
        if not seeds:
            raise ValueError("no seeds to run")
        self.cfg = cfg
        self.system = GimbalSystem(cfg.world_config())
        self.model = identified_model(self.system)
        self.Te = self.system.Te
        self.steps = int(round(cfg.run_seconds / self.Te))
        # The system's world serves the first run; the others share its model unless a
        # disturbance changes the model (a water current sets its medium velocity).
        share = not any(parse_disturbance(d).changes_model for d in cfg.disturbances)
        worlds = build_worlds(self.system.config, len(seeds), self.system.world, share)
        self.runs = [LoopRun(cfg, int(s), self.system, self.model, w, self.steps, record)
                     for s, w in zip(seeds, worlds, strict=True)]
        # The runs' vehicles as one (each started as its own): one pass steps them all.
        self.vehicles = None
        if self.runs[0].vehicle is not None:
            self.vehicles = Vehicle.stacked([run.vehicle for run in self.runs])
            for i, run in enumerate(self.runs):
                run.vehicle = self.vehicles.row(i)
        self.threads = max(1, min(int(threads), len(self.runs)))
        self.on_step = on_step

    def run(self, keep_trace: bool | Sequence[bool] = False,
            progress: bool = False, window: float | None = None) -> list[RunOutcome]:
        """Run every seed; one :class:`RunOutcome` per seed (in order). ``keep_trace``:
        for all runs, or one flag per run; ``window`` [s]: also the metrics of each
        window of that length (:mod:`ledsim.loop.windows`). The real-time factor of each
        is the simulated seconds over the wall time, times N (the throughput per
        run)."""
        runs, n, Te = self.runs, len(self.runs), self.Te
        keep = [keep_trace] * n if isinstance(keep_trace, bool) else list(keep_trace)
        t0 = time.perf_counter()
        # The tick of every world (physics.tick.advance in parts): torques commanded,
        # then physics.tick.step_worlds.
        sensors = SensorRows([run.sensor for run in runs])
        with PhysicsPass([run.world for run in runs], self.threads) as physics:
            for k in tqdm(range(self.steps), disable=not progress, desc="simulate",
                          leave=False, file=sys.stderr):
                t = k * Te
                for run, reading in zip(runs, sensors.read(), strict=True):
                    torque = run.control(k, t, reading)
                    if self.on_step is not None:
                        self.on_step(run, t)
                    run.applied[k] = run.world.set_torque(torque)
                t_next = (k + 1) * Te
                step_worlds(physics, [(run.world, run.disturbances, t_next) for run in runs],
                            self.vehicles, t_next)
                if (k + 1) % REPORT_EVERY == 0:  # the share done, for run_jobs' bar
                    report_progress((k + 1) / self.steps)
        wall = time.perf_counter() - t0
        times = np.arange(self.steps) * Te
        return [outcome(RunRecord(
                    run.result(times), run.xhat, run.flags, run.disturbances, run.supervised,
                    run.spent,
                    None if run.station is None else
                    Navigation(run.hull, run.station, run.navigated),
                    run.vehicle is not None and run.vehicle.station_keeping,
                    None if run.given is None else
                    run.given.series(run.step.estimator, self.cfg, run.u, run.measured),
                    run.noise, (self.model, run.u, run.measured), run.outside, run.medium,
                    run.own, run.reseeded, run.xhat_std),
                    self.cfg, self.system.constants, wall / n, keep[i], window)
                for i, run in enumerate(runs)]


def run_batch(cfg: RunConfig, seeds: Sequence[int], keep_trace: bool | Sequence[bool] = False,
              threads: int = 1, window: float | None = None) -> list[RunOutcome]:
    """The runs of ``cfg`` for ``seeds``, stepped together (see :class:`ClosedLoop`);
    a kept trace holds what the estimator was given."""
    keep = keep_trace if isinstance(keep_trace, bool) else any(keep_trace)
    return ClosedLoop(cfg, seeds, threads, record=keep).run(keep_trace, window=window)


def run_once(cfg: RunConfig, seed: int, keep_trace: bool = False, on_step=None,
             progress: bool = False, window: float | None = None) -> RunOutcome:
    """One closed-loop run (see :class:`ClosedLoop`)."""
    return ClosedLoop(cfg, [seed], on_step=on_step, record=keep_trace).run(
        keep_trace, progress, window)[0]
