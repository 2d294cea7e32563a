"""The loop closed in physics: one seed or many, through the one control step.

MuJoCo supplies the true angle, the ray sensors the two powers (every seed's read in
one pass: :class:`~ledsim.physics.sensor_rows.SensorRows`), and each seed's
:class:`~ledsim.agent.step.ControlStep` (dropout gate, supervisor with its estimator,
control law, motor) turns them into a motor torque; one tick of
:class:`~ledsim.physics.world_rows.WorldRows` moves every world on. :class:`ClosedLoop`
steps the runs of several seeds together, their physics split over threads (MuJoCo
steps without the GIL); a run of one seed is the same code with N = 1, so a seed's
numbers are the same whatever else runs beside it. Every run of a seed sees the same
sensor-noise draws and disturbances whatever the estimator.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence

import numpy as np
from tqdm.auto import tqdm

from ledsim.agent.head_supervisor import HeadSupervisor
from ledsim.agent.node_cue import NodeCue
from ledsim.agent.supervisor import LinkSupervisor
from ledsim.experiment.montecarlo import report_progress
from ledsim.loop.build import SeedRun, build_run
from ledsim.loop.given import GivenRecord
from ledsim.loop.outcome import Navigation, RunOutcome, RunRecord, outcome
from ledsim.loop.run_config import RunConfig
from ledsim.physics.gimbal_system import GimbalSystem
from ledsim.physics.sensor import SensorReading
from ledsim.physics.simulation import SimulationResult
from ledsim.physics.world_rows import WorldRows

#: Steps between two reports of a run's progress (montecarlo.report_progress).
REPORT_EVERY = 50


class LoopRun:
    """One seed of a closed-loop run: its world, sensor, disturbances, control step, and
    the record of every step (``steps`` rows); with ``record``, also what its estimator
    was given (:mod:`ledsim.loop.given`)."""

    def __init__(self, built: SeedRun, system: GimbalSystem, steps: int, aided: bool,
                 record: bool = False):
        self.seed, self.world, self.noise = built.seed, built.world, built.noise
        self.sensor, self.disturbances = built.sensor, built.disturbances
        self.vehicle, self.step, self._latest = built.vehicle, built.step, built.latest
        self.aided = aided
        self.given = GivenRecord(steps) if record else None
        self.supervised = isinstance(self.step.supervisor, LinkSupervisor | HeadSupervisor)
        lay = system.constants.layout
        npd, nx = lay.n_photodiodes, lay.n_state
        # u and the torque: one float a step for one axis, one per axis for more
        self.axes = lay.n_axes
        per_axis = () if self.axes == 1 else (self.axes,)
        self.geo = np.empty((steps, 4, npd))  # distance, theta, phi, visible fraction
        self.state = np.empty((steps, nx))
        self.gimbal = np.empty((steps, nx))
        self.hull = np.empty((steps, 3))
        self.power = np.empty((steps, npd))
        self.clean = np.empty((steps, npd))
        self.applied = np.empty((steps, *per_axis))
        self.xhat = np.empty((steps, nx))  # what the run reports (held while lost)
        self.own = np.empty((steps, nx))  # the estimator's own estimate
        self.xhat_std = np.full((steps, nx), np.nan)  # the held estimate's std (NaN: none)
        self.flags = np.zeros((steps, 2), dtype=bool)  # lost, acquiring
        self.reseeded = np.zeros(steps, dtype=bool)  # the supervisor restarted the estimator
        # What the estimator was told and given (for the bound): u [rad/s^2], samples.
        self.u = np.zeros((steps, *per_axis))
        self.measured = np.ones((steps, npd), dtype=bool)
        self.outside = np.zeros(steps, dtype=bool)  # the estimator left its training box
        # The medium's factor on the reference photodiode's power (scintillation): the
        # most it could receive fades with it, so a fade is not a pointing loss.
        self.medium = np.ones(steps)
        # The vehicle's navigated position [m] and its station (None: no vehicle).
        self.navigated = np.full((steps, 3), np.nan)
        v = self.vehicle
        self.station = None if v is None else np.r_[v.home[0], v.surface]
        # a mission's station moves: its target each step (the hull's error is from it)
        self.moving = v is not None and v.paths[0] is not None
        self.cue = None  # where the navigation puts the node (a pan-tilt on the move)
        if self.moving:
            self.station = np.tile(self.station, (steps, 1))
            if self.axes == 2 and hasattr(self.step, "tell_node"):
                self.cue = NodeCue(self.world.led_pos, self.world.led_rotation[:, 2],
                                   self.world.gimbal_in_hull(), v.navigation,
                                   built.node_error, np.random.default_rng([self.seed, 49]))
                self.step.anchor(*self.cue.reference)
        self.spent = 0.0  # s in the control step

    def control(self, k: int, t: float, reading: SensorReading | None = None) -> float:
        """Record the sensor's ``reading`` at step ``k`` (time ``t`` [s]; None: read it
        now), and return the motor torque [N m] the control step commands (per axis)."""
        r = self._latest.reading = self.sensor.read() if reading is None else reading
        self.geo[k] = r.distance, r.emission_angle, r.incidence_angle, r.visible_fraction
        if self.axes == 1:
            self.state[k] = r.phi, r.phidot
            q, qdot = r.gimbal_angle, r.gimbal_rate
            self.gimbal[k] = q, qdot
        else:
            self.state[k] = r.x
            q, qdot = self.world.gimbal_angles, self.world.gimbal_rates
            self.gimbal[k, :self.axes], self.gimbal[k, self.axes:] = q, qdot
        self.hull[k], self.power[k], self.clean[k] = r.hull_pos, r.power, r.power_clean
        if self.world.light_gain is not None:
            self.medium[k] = self.world.light_gain[self.world.config.constants.layout.reference]
        if self.vehicle is not None:
            self.navigated[k] = self.vehicle.navigated_position
            if self.moving:
                self.station[k] = self.vehicle.target
                if self.cue is not None:  # the pan-tilt's cue, filters' gain and levels
                    navigated = self.vehicle.navigation
                    self.step.tell_node(self.cue.at(navigated))
        t0 = time.perf_counter()
        los = None
        if self.aided:  # a pan-tilt head takes the gyro's three rates (agent/pan_tilt.py)
            if self.axes == 1:
                los = self.vehicle.los
            elif (nav := self.vehicle.reading) is not None:  # none before it first acts
                los = nav.gyro
        torque = self.step(r.power, t, q, qdot, los)
        if self.cue is not None and (look := self.step.look()) is not None:
            self.cue.learn(navigated, look)  # where the head finds the LED
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

    @property
    def reading(self) -> SensorReading | None:
        """The sensor's last reading."""
        return self._latest.reading

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
        built = build_run(cfg, seeds, record)
        self.system, self.model, self.steps = built.system, built.model, built.steps
        self.Te = self.system.Te
        self.built = built
        self.runs = [LoopRun(b, self.system, self.steps, built.aided, record)
                     for b in built.seeds]
        # The runs' vehicles as one (each started as its own): one pass steps them all.
        self.threads = max(1, min(int(threads), len(self.runs)))
        # The runs' worlds as rows that tick together; their vehicles as one (each
        # started as its own): one pass steps them all.
        self.rows = WorldRows([run.world for run in self.runs], self.threads)
        rows = self.rows.start([run.sensor for run in self.runs],
                               [run.disturbances for run in self.runs],
                               [run.vehicle for run in self.runs])
        for run, vehicle in zip(self.runs, rows, strict=True):
            run.vehicle = vehicle
        self.vehicles = self.rows.vehicles
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
        # The tick of every world (physics.tick.advance in parts): each run's control
        # step on its reading, then the rows' torques, physics, preparation and
        # vehicles in one tick.
        torques = [0.0] * n
        with self.rows as rows:
            for k in tqdm(range(self.steps), disable=not progress, desc="simulate",
                          leave=False, file=sys.stderr):
                t = k * Te
                for i, (run, reading) in enumerate(zip(runs, rows.read(), strict=True)):
                    torques[i] = run.control(k, t, reading)
                    if self.on_step is not None:
                        self.on_step(run, t)
                for run, applied in zip(runs, rows.tick((k + 1) * Te, torques=torques),
                                        strict=True):
                    run.applied[k] = applied
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
                    run.given.series(run.step.estimator, self.built.header,
                                     self.system.constants.layout, run.u, run.measured),
                    run.noise, (self.model, run.u, run.measured), run.outside, run.medium,
                    run.own, run.reseeded, run.xhat_std),
                    self.built.judging, self.system.constants, wall / n, keep[i], window)
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
