"""Which estimator a closed-loop run uses, and the models it computes with.

The Bayesian filters (EKF, UKF, particle filter) use the identified one-step model of
the run's own world. The KKL, without ``--checkpoint`` and under supervision, is the
shipped gain-scheduled KKL of :data:`REFERENCE_DISTANCE` (:mod:`observer.kkl.scheduled`):
the supervisor rescales the powers to the reference gain and tells the observer the
noise those rescaled powers carry, which sets its gain's floor and its decoder. One
observer thus serves every distance. ``kkl-bank`` is the former default: the bank of
fixed-gain observers trained for the noise levels :data:`BANK_NOISE`
(:class:`observer.kkl.bank.ObserverBank`), which runs the member for the noise measured.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

from ledsim.constants import PAPER_DISTANCE
from ledsim.experiment.estimators import LOOP_KKL_ESTIMATORS, build_estimator
from ledsim.files.resources import require_shipped_checkpoint
from ledsim.loop.run_config import RunConfig
from ledsim.physics.gimbal_system import GimbalSystem, IdentifiedGimbalModel
from ledsim.physics.scene import WorldConfig
from ledsim.radiometry.link_presets import kkl_reference_constants, preset_named
from ledsim.radiometry.optics import peak_power
from observer.kkl import checkpoint as ckpt
from observer.kkl.bank import ObserverBank
from observer.noise import MeasurementNoise

#: Distance [m] of the shipped MuJoCo KKL bank that serves every distance.
REFERENCE_DISTANCE = PAPER_DISTANCE
#: The bank's members: measurement noise over the nominal [-] and observer preset.
#: Rescaled to the reference gain, the nominal noise is about 6x at d = 0.2 m and 13x at
#: 0.3 m; the slower filters of the low-light preset pay off only on the weakest link.
BANK = ((1.0, "default"), (3.0, "default"), (6.0, "default"), (13.0, "low-light"))
#: Link distances [m] the shipped bank is measured to serve (``docs/disturbances.md``).
SERVED_DISTANCES = (0.05, 0.3)


#: The loop's KKL estimators (the registry's): ``kkl`` (under supervision the
#: gain-scheduled KKL, without it the shipped observer of the distance),
#: ``kkl-scheduled`` (always the scheduled one) and ``kkl-bank`` (the bank of fixed-gain
#: observers that was ``kkl`` before).
KKL_ESTIMATORS = LOOP_KKL_ESTIMATORS


def served(cfg: RunConfig) -> bool:
    """Whether the run's KKL is a shipped one of the reference distance (scheduled or
    the bank) at a distance it is measured to serve (True for every other estimator,
    for a KKL of the user's own checkpoint, and on a physical link, whose KKL is
    measured across its range in docs/link_table.md)."""
    lo, hi = SERVED_DISTANCES
    return (not uses_reference(cfg) or preset_named(cfg.link).kkl_measured_everywhere
            or lo <= cfg.distance <= hi)


def saturates(cfg: RunConfig) -> bool:
    """Whether the run's receiver saturates anywhere along its path: at its distance
    or where the transmitter's drift brings it
    (:func:`~ledsim.loop.path_range.saturation_onset`)."""
    from ledsim.loop.path_range import saturation_onset

    return saturation_onset(cfg) is not None


#: On a physical link, the scheduled KKL holds its gain while the motor works against
#: a load (mean |u| above this [rad/s^2]; quiet water: 0.01-0.02, beam seas and
#: currents: 0.5-2): GainSchedule.driven. None: the paper's schedule everywhere.
DRIVEN_LEVEL: float | None = 0.3
DRIVEN_GAIN = 2.0


def reference_world(cfg: RunConfig) -> WorldConfig:
    """The world the run's shipped KKL was trained in: the bench at
    :data:`REFERENCE_DISTANCE`, or on a physical link the bench with the physical
    receiver (:func:`~ledsim.radiometry.link_presets.kkl_reference_constants`)."""
    # The bench's own water: the tracker takes another water's attenuation as a gain;
    # and the bench's level LED (the models know only the turning plane).
    ref = replace(cfg, water=None, attenuation=None, transmitter_depth=None).world_config(
        distance=REFERENCE_DISTANCE)
    if preset_named(cfg.link).trains_on_own_receiver:
        return ref
    return replace(ref, constants=kkl_reference_constants())


def uses_reference(cfg: RunConfig) -> bool:
    """Whether the run's KKL is of the reference distance, the gain tracker serving
    every other: the scheduled KKL, or the bank."""
    if cfg.estimator == "kkl-scheduled":
        return True
    return cfg.estimator in ("kkl", "kkl-bank") and cfg.supervision and not cfg.checkpoint


BANK_NOISE = tuple(s for s, _ in BANK)


def bank_preset(noise: float) -> str:
    """Observer preset of the bank member for ``noise`` (``"default"`` off the bank)."""
    return dict(BANK).get(noise, "default")

_MODELS: dict = {}


def identified_model(system: GimbalSystem) -> IdentifiedGimbalModel:
    """The fitted one-step model of this world (cached per process and world); of a
    pan-tilt head's (:class:`~ledsim.physics.head_system.HeadSystem`), its four-state
    :class:`~ledsim.physics.head_model.HeadModel`."""
    key = json.dumps(system.metadata(), sort_keys=True)
    if key not in _MODELS:
        _MODELS[key] = system.model() if hasattr(system, "home") else \
            IdentifiedGimbalModel.fit(system)
    return _MODELS[key]


def identified_model_of(world: WorldConfig) -> IdentifiedGimbalModel:
    """:func:`identified_model` of ``world``, fitted on a system of its own (fitting sets
    and steps MuJoCo's state), both built once per process: for code that steps a world
    of its own (the environment's policy and wrapper)."""
    return identified_model(member_system(world))


_MEMBER_SYSTEMS: dict = {}


def member_system(world: WorldConfig) -> GimbalSystem:
    """The model system of a bank member's world, built once per process: it only
    supplies constants, metadata and h (which sets its own state before each use), so
    runs may share it; compiling the scene is most of a short run's set-up."""
    if world not in _MEMBER_SYSTEMS:
        _MEMBER_SYSTEMS[world] = GimbalSystem(world)
    return _MEMBER_SYSTEMS[world]


@dataclass(frozen=True)
class KKLMember:
    """One KKL of a run: its noise level over the nominal [-], its checkpoint, and the
    world it was trained in (which its metadata is checked against)."""

    noise: float
    checkpoint: Path
    world: WorldConfig


def noisier(world: WorldConfig, scale: float) -> WorldConfig:
    """``world`` with the measurement-noise standard deviation times ``scale``."""
    c = world.constants
    return replace(world, constants=replace(
        c, measurement_noise_var=c.measurement_noise_var * scale * scale))


def kkl_members(cfg: RunConfig) -> list[KKLMember]:
    """The KKL observers of a run. ``kkl``: ``cfg.checkpoint``, the shipped observer of
    the distance (without supervision) or the shipped gain-scheduled KKL of the
    reference distance (with it; on a physical link the physical receiver's);
    ``kkl-scheduled``: that one always (or ``cfg.checkpoint``, trained there);
    ``kkl-bank``: the shipped bank (with supervision). The gain tracker serves every
    distance from the reference one."""
    ref = reference_world(cfg)
    if cfg.estimator == "kkl-scheduled" or (cfg.estimator == "kkl" and cfg.supervision
                                            and not cfg.checkpoint):
        path = Path(cfg.checkpoint) if cfg.checkpoint else require_shipped_checkpoint(
            REFERENCE_DISTANCE, "mujoco",
            design=preset_named(cfg.link).scheduled_design)
        return [KKLMember(1.0, path, ref)]
    if cfg.checkpoint:
        return [KKLMember(1.0, Path(cfg.checkpoint), cfg.world_config())]
    if not cfg.supervision:
        return [KKLMember(1.0, require_shipped_checkpoint(cfg.distance, "mujoco"),
                          cfg.world_config())]
    design = preset_named(cfg.link).kkl_design
    return [KKLMember(s, require_shipped_checkpoint(REFERENCE_DISTANCE, "mujoco", design,
                                                    noise=s),
                      noisier(ref, s)) for s in BANK_NOISE]


def loop_checkpoint(cfg: RunConfig) -> Path:
    """The (first) KKL checkpoint of a run."""
    return kkl_members(cfg)[0].checkpoint


def check_checkpoint(cfg: RunConfig) -> None:
    """Fail fast (before any worker starts) on a checkpoint that does not fit (a pan-tilt
    pair: each half against its axis's system in the world it was trained in)."""
    if cfg.world.two_axes:
        if cfg.estimator == "kkl":
            from ledsim.loop.build.head_kkl import AXES, pair_paths, reference_axes, shipped_axis

            for name, system in zip(AXES, reference_axes(cfg.lens_field_deg), strict=True):
                path = shipped_axis(name, cfg.lens_field_deg) if not cfg.checkpoint else \
                    pair_paths(cfg.checkpoint)[name]
                if path.is_file():  # a missing one is refused, naming it, as the run builds
                    ckpt.load(path, system)
        return
    if cfg.estimator in KKL_ESTIMATORS:
        for m in kkl_members(cfg):
            ckpt.load(m.checkpoint, member_system(m.world))  # the run's own, built once


def run_noise(cfg: RunConfig, system: GimbalSystem) -> MeasurementNoise:
    """The measurement noise of a run of ``cfg`` in ``system``'s world: the link's at
    the run's noise scale."""
    return system.measurement_noise.scaled(cfg.noise_scale)


def loop_estimator(cfg: RunConfig, system: GimbalSystem, model: IdentifiedGimbalModel,
                   noise: MeasurementNoise | None = None):
    """(estimator, the system whose gain its model has) for a run in ``system``'s world
    with the measurement noise ``noise`` (None: :func:`run_noise`); the estimator is
    None for the oracle."""
    if cfg.estimator not in KKL_ESTIMATORS:
        if cfg.filter_distance == "nominal":
            # What the KKL knows: the reference distance's model, and the supervisor's
            # gain tracker for the rest; the sensor's noise, rescaled to the model's gain
            # by the distance's prior (as the KKL bank picks its member).
            ref = replace(cfg, transmitter_depth=None).world_config(distance=REFERENCE_DISTANCE)
            prior = peak_power(system.constants) / peak_power(ref.constants)
            noise = run_noise(cfg, system) if noise is None else noise
            system = member_system(noisier(ref, noise.scale / prior))
            model = identified_model(system)
        # Under supervision a loss is the supervisor's to handle, for every estimator
        # alike: the particle filter's own re-draw fired on half-occluded samples and kicks.
        est = build_estimator(cfg.estimator, system, model=model, particles=cfg.particles,
                              redraw=not cfg.supervision)
        if cfg.filter_distance != "nominal":  # the nominal model carries it already
            scale = (run_noise(cfg, system) if noise is None else noise).scale
            if scale != 1.0:
                est.tell_noise_scale(scale)
        return est, system
    members = kkl_members(cfg)
    first = members[0].world
    ref = system if first == system.config else member_system(first)
    # The KKL's model (Omega's f, and the h that fills missing samples and that the
    # supervisor checks): the identified model; or the simulator in a world of its own,
    # since its f and h reset MuJoCo's state to evaluate a step. Never the run's own
    # world: without Omega ("none") the identified model still supplies h.
    if cfg.omega_model == "simulator":
        omega_f = GimbalSystem(first)
    else:
        omega_f = identified_model(ref)
    observers = [build_estimator("kkl", ref if m.world == first else member_system(m.world),
                                 model=omega_f, checkpoint=m.checkpoint,
                                 use_omega=cfg.omega_model != "none") for m in members]
    if preset_named(cfg.link).holds_gain_when_driven and DRIVEN_LEVEL is not None:
        for o in observers:
            if hasattr(o, "schedule"):
                o.schedule = replace(o.schedule, driven=DRIVEN_LEVEL,
                                     driven_gain=DRIVEN_GAIN)
    if len(observers) == 1:
        return observers[0], ref
    # A switch waits 2 s: a vibrating hull moves the gain for a moment, not for good.
    return ObserverBank(observers, [m.noise for m in members],
                        dwell=int(round(2.0 / system.Te))), ref
