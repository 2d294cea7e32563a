"""Checks of a run's configuration: every choice in its registry, every number in its
physical range, refused in one line naming the value and what is allowed."""

from __future__ import annotations

import functools
import math
import types
import typing

from ledsim.agent.autopilot import StationKeeping
from ledsim.constants import (
    MIN_BIT_RATE,
    MIN_DISTANCE,
    MIN_NOISE_SCALE,
    PAPER_DISTANCE,
    LinkConstants,
    NavigationNoise,
)
from ledsim.errors import LedsimError, check_ranges
from ledsim.experiment.estimators import LOOP_KKL_ESTIMATORS
from ledsim.keyvalues import settings_of
from ledsim.loop.head_validation import _check_lens, _check_two_axes
from ledsim.loop.mission_scenarios import MISSION_SCENARIOS
from ledsim.loop.registry import (
    ACQUISITIONS,
    FILTER_DISTANCES,
    GIMBALS,
    LOOP_ESTIMATORS,
    MAX_INITIAL_ANGLE,
    MIN_RUN_PEAK_SNR,
    OMEGA_MODELS,
    PHYSICS_SCENARIOS,
    RECEIVERS,
    SCANNING_ESTIMATORS,
    peak_snr,
)
from ledsim.physics.disturbances import check_sea, check_timing, parse_disturbance
from ledsim.physics.scene import WorldConfig, transmitter_rise
from ledsim.physics.sea_scene import seabed_check
from ledsim.radiometry.link_presets import LINK_PRESETS, preset_named
from ledsim.radiometry.water import WATER_TYPES


def navigation_noise(settings: tuple[str, ...]) -> NavigationNoise:
    """:class:`~ledsim.constants.NavigationNoise` with ``key=value`` ``settings`` applied;
    a bad key or value raises :class:`LedsimError` naming it."""
    return settings_of(NavigationNoise, settings, "--imu-noise", LedsimError,
                       integers=("encoder_bits",))


def keeping_gains(settings: tuple[str, ...]) -> StationKeeping:
    """:class:`~ledsim.agent.autopilot.StationKeeping` with ``key=value`` ``settings``
    applied; a bad key or value raises :class:`LedsimError` naming it."""
    return settings_of(StationKeeping, settings, "--station-keeping-gain", LedsimError)


#: The KKL estimators (on a physical link only under supervision): the registry's.
KKL_ON_BENCH = LOOP_KKL_ESTIMATORS


def validate_run(cfg) -> None:
    """Raise :class:`LedsimError` naming the first thing ``cfg`` (a
    :class:`~ledsim.loop.run_config.RunConfig`) does not allow."""
    for flag, value, registry in (("scenario", cfg.scenario, PHYSICS_SCENARIOS),
                                  ("estimator", cfg.estimator, LOOP_ESTIMATORS),
                                  ("--omega-model", cfg.omega_model, OMEGA_MODELS),
                                  ("--filter-distance", cfg.filter_distance,
                                   FILTER_DISTANCES),
                                  ("--acquisition", cfg.acquisition, ACQUISITIONS),
                                  ("--link", cfg.link, LINK_PRESETS),
                                  ("--gimbal", cfg.world.head[0], GIMBALS),
                                  ("--receiver", cfg.world.head[1], RECEIVERS)):
        if value not in registry:
            raise LedsimError(f"unknown {flag.lstrip('-')} {value!r}: choose one of "
                              f"{', '.join(registry)}")
    gimbal, receiver = cfg.world.head
    if GIMBALS[gimbal] != receiver:
        raise LedsimError(f"--receiver {receiver} does not fit --gimbal {gimbal}: the "
                          f"{gimbal} gimbal carries the {GIMBALS[gimbal]} (the "
                          f"{receiver} needs --gimbal {RECEIVERS[receiver]})")
    if cfg.world.two_axes:
        _check_two_axes(cfg)
    elif cfg.estimator in SCANNING_ESTIMATORS:
        raise LedsimError(f"estimator {cfg.estimator!r} runs on the pan-tilt head only "
                          "(it scans its data detector): use --gimbal pan-tilt on a "
                          "physical --link")
    elif cfg.channel_mismatch:
        raise LedsimError(f"--channel-mismatch {cfg.channel_mismatch:g} is not allowed "
                          "with --receiver pair: it mismatches the quad's pointing pairs")
    elif cfg.initial_elevation != 0.0:
        raise LedsimError(f"--initial-elevation {cfg.initial_elevation:g} is not allowed "
                          "with --gimbal yaw: only a pan-tilt head turns in elevation")
    if cfg.lens_field_deg is not None:
        _check_lens(cfg)
    if cfg.water is not None and cfg.water not in WATER_TYPES:
        raise LedsimError(f"unknown water {cfg.water!r}: choose one of "
                          f"{', '.join(WATER_TYPES)}")
    preset = preset_named(cfg.link)
    if not preset.ships_fixed_kkls and not cfg.checkpoint and (
            cfg.estimator in KKL_ON_BENCH and not cfg.supervision):
        alone = "" if cfg.supervision else " with --no-supervision"
        raise LedsimError(f"estimator {cfg.estimator!r}{alone} has no shipped observer for "
                          f"--link "
                          f"{cfg.link}: on a physical link the shipped KKLs (the "
                          "gain-scheduled one and the bank) run under supervision, which "
                          "maps the link onto the world they were trained in; or use ekf, "
                          "ukf, pf or oracle")
    if not preset.nominal_filters and cfg.filter_distance == "nominal":
        raise LedsimError("--filter-distance nominal is not allowed with a physical --link: "
                          "it rescales the bench's noise (use configured)")
    if cfg.estimator == "kkl-scheduled" and not cfg.supervision and \
            not cfg.checkpoint and not math.isclose(cfg.distance, PAPER_DISTANCE):
        raise LedsimError(f"estimator 'kkl-scheduled' with --no-supervision runs only "
                          f"at --distance {PAPER_DISTANCE:g} (got {cfg.distance:g}): "
                          "elsewhere it needs the supervisor's gain tracker")
    if cfg.filter_distance == "nominal" and not cfg.supervision:
        raise LedsimError("--filter-distance nominal is not allowed with "
                          "--no-supervision: the filters then need the supervisor's "
                          "gain tracker")
    checks = [("--distance", cfg.distance, cfg.distance >= MIN_DISTANCE,
               f">= {MIN_DISTANCE:g} m"),
              ("--torque-limit", cfg.torque_limit, cfg.torque_limit > 0, "> 0 N m"),
              ("--seeds", cfg.seeds, cfg.seeds >= 1, ">= 1"),
              ("--noise-scale", cfg.noise_scale, cfg.noise_scale >= MIN_NOISE_SCALE,
               f">= {MIN_NOISE_SCALE:g}"),
              ("--particles", cfg.particles, cfg.particles >= 1, ">= 1")]
    if cfg.seconds is not None:
        Te = LinkConstants().Te
        checks.append(("--seconds", cfg.seconds, cfg.seconds >= Te,
                       f">= {Te:g} s (one control period)"))
    if cfg.window is not None:
        checks.append(("--window", cfg.window, cfg.window > 0, "> 0 s"))
    if cfg.initial_angle is not None:
        checks.append(("--initial-angle", cfg.initial_angle,
                       abs(cfg.initial_angle) <= MAX_INITIAL_ANGLE,
                       f"in [-{MAX_INITIAL_ANGLE:g}, {MAX_INITIAL_ANGLE:g}] rad"))
    checks.append(("--channel-mismatch", cfg.channel_mismatch,
                   0.0 <= cfg.channel_mismatch <= 0.5, "in [0, 0.5]"))
    checks.append(("--initial-elevation", cfg.initial_elevation,
                   abs(cfg.initial_elevation) <= MAX_INITIAL_ANGLE,
                   f"in [-{MAX_INITIAL_ANGLE:g}, {MAX_INITIAL_ANGLE:g}] rad"))
    if cfg.attenuation is not None:
        checks.append(("--attenuation", cfg.attenuation, 0 <= cfg.attenuation <= 100,
                       "in [0, 100] 1/m"))
    if cfg.bit_rate is not None:
        checks.append(("--bit-rate", cfg.bit_rate, MIN_BIT_RATE <= cfg.bit_rate <= 1e10,
                       f"in [{MIN_BIT_RATE:g}, 1e10] bit/s"))
    checks.append(("--depth", cfg.depth, 1.0 <= cfg.depth <= 500.0, "in [1, 500] m"))
    checks.append(("--node-error", cfg.node_error, 0.0 <= cfg.node_error <= 100.0,
                   "in [0, 100] m"))
    if cfg.transmitter_depth is not None:
        checks.append(("--transmitter-depth", cfg.transmitter_depth,
                       0.2 <= cfg.transmitter_depth <= 500.0, "in [0.2, 500] m"))
    check_ranges(checks)
    transmitter_rise(cfg.depth, cfg.transmitter_depth, cfg.distance,
                     ("--depth", "--transmitter-depth"))
    if cfg.sea_depth is not None:
        check_ranges([seabed_check(cfg.sea_depth, cfg.depth, cfg.transmitter_depth,
                                   ("--sea-depth", "--depth", "--transmitter-depth"))])
    disturbances = [parse_disturbance(d) for d in cfg.disturbances]
    if not preset.has_receiver_hardware:
        for d in disturbances:
            if getattr(d, "needs_receiver", False):
                raise LedsimError(d.NO_RECEIVER)
    check_timing(disturbances, cfg.run_seconds)
    check_sea(disturbances, cfg.depth, cfg.transmitter_depth, cfg.sea_depth)
    if cfg.window is not None and cfg.window > cfg.run_seconds:
        length = "--seconds" if cfg.seconds is not None else \
            f"the {cfg.scenario} scenario's length; --seconds sets it"
        raise LedsimError(f"--window {cfg.window:g} is not allowed: it is longer than the "
                          f"{cfg.run_seconds:g} s run ({length}): must be in (0, "
                          f"{cfg.run_seconds:g}] s")
    if cfg.node_error and cfg.mission_plan is None:
        raise LedsimError(f"--node-error {cfg.node_error:g} is what a vehicle on the move "
                          "believes of the node: it needs a --mission or a mission scenario")
    navigation_noise(cfg.imu_noise)
    keeping_gains(cfg.station_keeping_gains)
    if cfg.mission is not None or cfg.scenario in MISSION_SCENARIOS:
        from ledsim.loop.mission_checks import check_mission

        check_mission(cfg)
    from ledsim.loop.path_range import check_saturation

    check_saturation(cfg)
    world = cfg.world_config()
    snr = peak_snr(world.constants, cfg.noise_scale)
    if not snr >= MIN_RUN_PEAK_SNR:
        water = "" if cfg.attenuation is None else f" in water of --attenuation " \
            f"{cfg.attenuation:g}/m"
        raise LedsimError(f"--link {cfg.link} at --distance {cfg.distance:g} m{water} "
                          f"leaves the receiver in the dark: its peak SNR is {snr:.3g}, "
                          f"under {MIN_RUN_PEAK_SNR:g}; a shorter --distance, clearer "
                          "water or a lower --noise-scale")
    check_world(world)


@functools.lru_cache(maxsize=32)
def check_world(config: WorldConfig):
    """Build the world of ``config`` once and look for the LED from each photodiode: a
    scene that cannot be built, or an LED that a photodiode cannot see whole (behind the
    receiver, or a beam that the seabed or the hull cuts, grazing included: the error
    names what cuts it), is refused before any run starts rather than in its first
    step. Raises :class:`~ledsim.physics.scene.WorldError`. Returns
    the scene's ids (:class:`~ledsim.physics.scene_ids.SceneIds`: which of the vehicle's
    sensors it has), cached with the check."""

    from ledsim.physics.sensor import IrradianceSensor
    from ledsim.physics.world import LinkWorld

    world = LinkWorld(config)
    IrradianceSensor(world, noise=False)
    return world.ids


def run_from_dict(cls, saved: dict):
    """The run of class ``cls`` (:class:`~ledsim.loop.run_config.RunSpec`) that a saved
    configuration describes (``asdict`` of one, through JSON, so its tuples are lists: by
    parts, or flat; a key it lacks keeps its default), checked: a key that is not a
    field, a value of another type, or a run :func:`validate_run` refuses raises
    :class:`LedsimError` naming it."""
    if not isinstance(saved, dict):
        raise LedsimError(f"a run configuration is a JSON object, not {type(saved).__name__}")
    parts = typing.get_type_hints(cls)
    by_parts = any(k in parts for k in saved)
    if by_parts:  # by parts: flatten, each part's keys its own
        flat = {}
        for part, values in saved.items():
            if part not in parts or not isinstance(values, dict):
                raise LedsimError(f"{part!r} in a run configuration by parts is not one "
                                  f"of its parts ({', '.join(parts)}) with its keys")
            flat.update(values)
        saved = flat
    hints = {k: v for kind in parts.values() for k, v in typing.get_type_hints(kind).items()}
    unknown = [k for k in saved if k not in hints]
    if unknown:
        raise LedsimError(f"unknown key {', '.join(map(repr, unknown))} in a run "
                          "configuration (one of another ledsim version?)")
    for key, value in saved.items():
        if not _fits(value, hints[key]):
            shown = repr(value)
            shown = shown if len(shown) <= 40 else shown[:37] + "..."
            raise LedsimError(f"{key} {shown} is not allowed: must be "
                              f"{_describe(hints[key])}")
    if not by_parts and saved.get("link", "paper") != "paper" and \
            saved.get("gimbal") is None and saved.get("receiver") is None:
        # ledsim's own saves (results.json's spec, a trace's config) are flat and name a
        # physical link's head since the pan-tilt became its default: one that does not
        # was saved before, on the yaw
        saved = {**saved, "gimbal": "yaw"}
    cfg = cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in saved.items()})
    validate_run(cfg)
    return cfg


def _fits(value, hint) -> bool:
    """Whether a JSON ``value`` is of the field type ``hint`` (an int is a float; a bool
    is neither; a list of str is a ``tuple[str, ...]``)."""
    if typing.get_origin(hint) in (types.UnionType, typing.Union):
        return any(_fits(value, h) for h in typing.get_args(hint))
    if typing.get_origin(hint) is tuple:
        return isinstance(value, list) and all(_fits(v, typing.get_args(hint)[0])
                                               for v in value)
    if hint is float:
        return isinstance(value, int | float) and not isinstance(value, bool)
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, hint)


def _describe(hint) -> str:
    """A field type in words: ``a number or null``, ``a list of strings``."""
    if typing.get_origin(hint) in (types.UnionType, typing.Union):
        return " or ".join(_describe(h) for h in typing.get_args(hint))
    if typing.get_origin(hint) is tuple:
        return "a list of strings"
    return {float: "a number", int: "an integer", bool: "true or false", str: "a string",
            type(None): "null"}.get(hint, hint.__name__)
