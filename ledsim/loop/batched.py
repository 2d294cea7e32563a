"""The closed loop of N runs at once: one configuration, N seeds, the same numbers.

:class:`BatchedClosedLoop` is :class:`~ledsim.loop.closed_loop.ClosedLoop` for a list
of seeds. Every stage takes all runs in one step:

- physics: :class:`~ledsim.physics.batch.WorldBatch` (one ``MjData`` per run, the worlds
  split over threads, which MuJoCo runs without the GIL);
- the sensor: :class:`~ledsim.physics.batch.BatchSensor` (closed form where the line of
  sight is provably clear, rays elsewhere; the noise drawn from each run's generator);
- the dropout gate, the control law and the warm-up hold on (N, ...) arrays;
- the estimator: :func:`observer.batched.batched` (KKL, EKF, UKF and particle filter
  vectorised). Under supervision (the default of ``ledsim run``) each run keeps its own
  supervisor and estimator (a bank of KKLs, acquisition scans), stepped in a loop: the
  same numbers, without the estimator's speed-up.

Each run gives what :func:`~ledsim.loop.closed_loop.run_once` gives for its seed, to
round-off (``tests/test_batched.py`` holds them to 1e-9).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from observer.batched import PerTrajectory, batched

from ..physics.batch import WorldBatch
from ..physics.batch_sensor import BatchSensor
from ..physics.disturbances import parse_disturbance
from ..physics.simulation import SimulationResult
from ..physics.system import GimbalSystem
from ..physics.world import LinkWorld
from .closed_loop import RunOutcome, hold_torque, make_supervisor, outcome, start_world
from .config import RunConfig
from .estimation import identified_model, loop_estimator
from .gate import BatchDropoutGate


class BatchedClosedLoop:
    """Runs of ``cfg`` for each of ``seeds``, stepped together.

    Args:
        cfg: the configuration (every run's).
        seeds: one run per seed.
        threads: threads stepping the physics (1: the calling thread).
    """

    def __init__(self, cfg: RunConfig, seeds: Sequence[int], threads: int = 1):
        self.cfg = cfg
        self.seeds = [int(s) for s in seeds]
        n = len(self.seeds)
        if n == 0:
            raise ValueError("no seeds to run")
        self.scenario = cfg.scenario_spec
        self.system = GimbalSystem(cfg.world_config())
        self.model = identified_model(self.system)
        constants = self.system.constants
        self.steps = int(round(cfg.run_seconds / constants.Te))
        self.supervised = cfg.supervision and cfg.estimator != "oracle"
        self.law = self.scenario.start_law(constants)
        self.gate = BatchDropoutGate(constants)
        # One estimator per run under supervision (each with its supervisor); otherwise
        # one template, vectorised.
        self.supervisors = []
        if cfg.estimator == "oracle":
            self.estimator = None
        elif self.supervised:
            members = []
            for s in self.seeds:
                est, est_system = loop_estimator(cfg, self.system, self.model)
                est.seed_run(s)
                est.reset()
                members.append(est)
                self.supervisors.append(make_supervisor(cfg, self.system, est, est_system,
                                                        self.law.tracks_beam))
            self.estimator = PerTrajectory(members)
        else:
            template, _ = loop_estimator(cfg, self.system, self.model)
            self.estimator = batched(template, n, seeded=lambda e, k: e.seed_run(
                self.seeds[k]))
        worlds, sensors, dists = [], [], []
        share = not any(parse_disturbance(d).changes_model for d in cfg.disturbances)
        for s in self.seeds:
            w = LinkWorld(self.system.config, share_model_of=worlds[0] if share and worlds
                          else None)
            sensor, d = start_world(cfg, self.system, w, s)
            worlds.append(w)
            sensors.append(sensor)
            dists.append(d)
        self.disturbances = dists
        self.q_hold = np.array([w.gimbal_angle for w in worlds])
        self.batch = WorldBatch(worlds, dists, threads)
        self.sensor = BatchSensor(self.batch, sensors, self.steps)
        self.spent = 0.0  # s in the estimators and the law

    def control(self, r, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(motor torques [N m], x_hat (N, 2), (lost, acquiring) flags (N, 2)) of step t."""
        n = len(self.seeds)
        flags = np.zeros((n, 2), dtype=bool)
        scan = np.full(n, np.nan)  # the acquisition scan's torques [N m] (NaN: none)
        warming_up = t < self.scenario.warmup
        if self.estimator is None:
            xhat = np.stack([r.phi, r.phidot], axis=-1)
        elif not self.supervised:
            xhat = self.estimator.update(self.gate(r.power))
        else:
            y = self.gate(r.power)
            xhat = np.empty((n, 2))
            for k, sup in enumerate(self.supervisors):
                d = sup.step(t, y[k], float(r.gimbal_angle[k]), float(r.gimbal_rate[k]))
                xhat[k] = d.xhat
                if d.torque is not None:
                    scan[k] = d.torque
                if d.reseeded:
                    self.law.restart(k)
                flags[k] = d.lost, d.acquiring
        inertia = self.system.inertia
        scanning = ~np.isnan(scan)
        u = np.zeros(n)
        steer = np.flatnonzero(~scanning)
        if not warming_up:
            u[steer] = self.law.batch(xhat, t, steer)
        u[scanning] = -scan[scanning] / inertia
        if self.estimator is not None:
            self.estimator.predict(u)
        if warming_up:
            torque = hold_torque(inertia, r.gimbal_angle, r.gimbal_rate, self.q_hold)
        else:
            torque = self.system.torque_for(u)
        torque = np.where(scanning, scan, torque) if scanning.any() else torque
        return torque, xhat, flags

    def run(self, keep_trace: bool | Sequence[bool] = False) -> list[RunOutcome]:
        """Run every seed; one :class:`RunOutcome` per seed (in order). ``keep_trace``:
        for all runs, or one flag per run. The real-time factor of each is the batch's
        simulated seconds over its wall time, times N (the throughput per run)."""
        n, steps, Te = len(self.seeds), self.steps, self.system.Te
        keep = [keep_trace] * n if isinstance(keep_trace, bool) else list(keep_trace)
        geo = np.empty((4, steps, n, 2))  # distance, theta, phi, visible fraction
        state = np.empty((steps, n, 2))
        gimbal = np.empty((steps, n, 2))
        hull = np.empty((steps, n, 3))
        power = np.empty((steps, n, 2))
        clean = np.empty((steps, n, 2))
        applied = np.empty((steps, n))
        xhats = np.empty((steps, n, 2))
        flags = np.empty((steps, n, 2), dtype=bool)
        t0 = time.perf_counter()
        try:
            for k in range(steps):
                t = k * Te
                r = self.sensor.read()
                geo[:, k] = r.distance, r.emission_angle, r.incidence_angle, \
                    r.visible_fraction
                state[k, :, 0], state[k, :, 1] = r.phi, r.phidot
                gimbal[k, :, 0], gimbal[k, :, 1] = r.gimbal_angle, r.gimbal_rate
                hull[k], power[k], clean[k] = r.hull_pos, r.power, r.power_clean
                c0 = time.perf_counter()
                torque, xhats[k], flags[k] = self.control(r, t)
                self.spent += time.perf_counter() - c0
                self.batch.step(torque, (k + 1) * Te)
                applied[k] = self.batch.applied
        finally:
            self.batch.close()
        wall = time.perf_counter() - t0
        times = np.arange(steps) * Te
        outs = []
        for i in range(n):
            res = SimulationResult(
                t=times, phi=state[:, i, 0], phidot=state[:, i, 1],
                gimbal_angle=gimbal[:, i, 0], gimbal_rate=gimbal[:, i, 1],
                torque=applied[:, i], power=power[:, i], power_clean=clean[:, i],
                incidence_angle=geo[2, :, i], emission_angle=geo[1, :, i],
                distance=geo[0, :, i], visible_fraction=geo[3, :, i],
                occluded=geo[3, :, i] < 1.0, hull_pos=hull[:, i])
            outs.append(outcome(res, xhats[:, i], flags[:, i], self.cfg,
                                self.system.constants, self.disturbances[i],
                                self.supervised, self.spent / n, wall / n, keep[i]))
        return outs


def run_batch(cfg: RunConfig, seeds: Sequence[int], keep_trace: bool | Sequence[bool] = False,
              threads: int = 1) -> list[RunOutcome]:
    """The runs of ``cfg`` for ``seeds``, stepped together (see
    :class:`BatchedClosedLoop`)."""
    return BatchedClosedLoop(cfg, seeds, threads).run(keep_trace)
