"""Each seed's control step, assembled from the run's configuration: the dropout gate,
the estimator (:mod:`ledsim.loop.build.estimation`) under its link supervisor, the
scenario's control law and the gimbal motor (``ledsim run``'s stack; the environment's
shipped policy assembles the same)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ledsim.agent.gate import DropoutGate
from ledsim.agent.head_supervisor import HeadSupervisor
from ledsim.agent.laws import intensity_maximum
from ledsim.agent.pan_tilt import HeadControlStep, HeadMotor
from ledsim.agent.range_gain import RangeGain
from ledsim.agent.slew import TimeOptimalSlew
from ledsim.agent.step import ControlStep, GimbalMotor, Unsupervised
from ledsim.agent.supervisor import LinkSupervisor
from ledsim.experiment.estimators import build_estimator
from ledsim.loop.build.estimation import loop_estimator, run_noise
from ledsim.loop.build.head_kkl import head_kkl
from ledsim.loop.registry import SCANNING_ESTIMATORS
from ledsim.loop.run_config import RunConfig
from ledsim.physics.axis_model import AxisRatioModel
from ledsim.physics.gimbal_system import GimbalSystem
from ledsim.physics.head_model import HeadModel
from ledsim.physics.head_system import HeadSystem
from ledsim.radiometry.optics import nominal_noise_std, peak_power
from observer.baselines.oracle import Oracle
from observer.noise import MeasurementNoise
from observer.recording import RecordingEstimator


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


def head_model(cfg: RunConfig, model: HeadModel) -> HeadModel:
    """The head's ``model`` told the run's calibration (its channels' gains)."""
    gains = cfg.world.channel_gains()
    return model if gains is None else model.calibrated(gains)


def head_estimator(cfg: RunConfig, system: HeadSystem, model: HeadModel,
                   noise: MeasurementNoise | None = None):
    """The estimator (not the oracle) of a pan-tilt run of ``cfg`` on the head's
    ``model`` (told the calibration, :func:`head_model`): the shipped KKL of each axis,
    or a filter in four states, told the run's noise scale."""
    est = head_kkl(model, cfg.lens_field_deg, cfg.checkpoint) if cfg.estimator == "kkl" \
        else \
        build_estimator(cfg.estimator, model, particles=cfg.particles)
    scale = (run_noise(cfg, system) if noise is None else noise).scale
    if scale != 1.0 and hasattr(est, "tell_noise_scale"):  # a filter's model's noise
        est.tell_noise_scale(scale)
    return est


def head_control_step(cfg: RunConfig, system: HeadSystem, model: HeadModel, seed: int,
                      truth: Callable[[], np.ndarray], record: bool = False,
                      noise: MeasurementNoise | None = None) -> ControlStep:
    """The control step of seed ``seed`` of a pan-tilt run of ``cfg``: the dropout gate,
    the estimator in four states on the head's ``model`` (the oracle reads ``truth``),
    with the minimum-time slew on both hinges at the start when the run acquires so, the
    scenario's law on both axes, and the motors holding the encoders' pointing during
    a warm-up; supervised (:class:`~ledsim.agent.head_supervisor.HeadSupervisor`: a
    fix from the quad, the minimum-time slew to it, loss detection and reacquisition)
    when the run is and its law tracks the beam."""
    spec = cfg.scenario_spec
    limit = system.config.torque_limit
    model = head_model(cfg, model)
    range_gain = level_gain = None
    if cfg.mission_plan is not None:  # on the move: gains at the navigation's range
        c = system.constants
        level_gain = RangeGain(None, cfg.distance, c.attenuation, order=c.lambertian_order)
        if cfg.estimator in ("ekf", "ukf", "pf", "scan-ekf"):
            model = model.calibrated(model.channel_gains)  # its own: its gain moves
            range_gain = RangeGain(model, cfg.distance, c.attenuation,
                                   order=c.lambertian_order)
    if cfg.estimator == "oracle":
        est = Oracle(system, truth)
    else:
        est = head_estimator(cfg, system, model, noise)
        if record:
            est = RecordingEstimator(est)
        est.seed_run(seed)
        est.reset()
    slew = TimeOptimalSlew(model.inertia, limit, system.Te)
    if cfg.supervision and spec.law.tracks_beam:
        ref = system.constants.layout.reference
        floor = (run_noise(cfg, system) if noise is None else noise).std
        # the scanning baselines track on the data detector alone: the quad's fix
        # acquires for them, but never corrects what they track
        supervisor = HeadSupervisor(est, [AxisRatioModel(model, a) for a in range(2)], slew,
                                    float(model.h(np.zeros(4))[ref]), ref, system.Te,
                                    floor=floor,
                                    corrects=cfg.estimator not in SCANNING_ESTIMATORS)
    elif cfg.fast_acquisition:  # the oracle's slew: its estimate is the truth
        supervisor = Unsupervised(est, slew, 0.0)
    else:
        supervisor = Unsupervised(est)
    motor = HeadMotor(model.inertia, system.home.copy(), limit=limit)
    # with the vehicle's gyro, each hinge's load observer on that axis's dynamics
    axes = [AxisRatioModel(model, a) for a in range(2)] if cfg.imu else None
    return HeadControlStep(dropout_gate(system.constants, supervisor), supervisor, spec.law,
                           system.constants, motor, spec.warmup, axes=axes,
                           range_gain=range_gain, level_gain=level_gain, home=system.home)


def dropout_gate(constants, supervisor) -> DropoutGate:
    """The gate in front of ``supervisor``. Past max_hold it passes a lasting darkness
    on, for a link supervisor to see as a blackout; an estimator alone cannot read
    darkness, so without supervision the gate holds every dark sample."""
    hold = {} if isinstance(supervisor, LinkSupervisor | HeadSupervisor) else \
        {"max_hold": math.inf}
    return DropoutGate(constants, **hold)
