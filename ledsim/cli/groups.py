"""Flag groups several ``ledsim`` commands share (the world, the scene, the run's knobs,
its start, the vehicle, the loop)."""

from __future__ import annotations

from ledsim.cli.spec_flags import add_spec_flags


def choices(registry) -> dict:
    return dict(choices=list(registry), metavar="{" + ",".join(registry) + "}")


def add_world_args(p, distance_help: str | None = None) -> None:
    """The world: its distance, link and scene (``distance_help``: this command's help
    for ``--distance``)."""
    add_spec_flags(p, "distance", **({} if distance_help is None else
                                     {"distance": {"help": distance_help}}))
    add_link_args(p)
    add_scene_args(p)


def add_link_args(p, sea: bool = True) -> None:
    """The physical link: its preset, the water and the data's bit rate (and, with
    ``sea``, the vehicles' depths)."""
    add_spec_flags(p, "link", "water", "attenuation", "bit_rate")
    if sea:
        add_spec_flags(p, "depth", "transmitter_depth", "sea_depth", "receiver_dome",
                       "transmitter_aimed")


def resolved_distance(args) -> float:
    """``--distance``, or the ``--link`` preset's default distance [m]."""
    from ledsim.radiometry.link_presets import DEFAULT_LINK, default_distance

    d = getattr(args, "distance", None)
    return default_distance(getattr(args, "link", DEFAULT_LINK)) if d is None else d


def add_scene_args(p) -> None:
    add_spec_flags(p, "scene", "integrator")


def add_run_knobs(p) -> None:
    """Knobs every run of ``run`` and ``sweep`` shares: length, particles, torque limit."""
    add_spec_flags(p, "torque_limit", "seconds", "particles")


def add_start_arg(p) -> None:
    """The run's start and acquisition (run, render, sweep)."""
    add_spec_flags(p, "acquisition", "initial_angle", "initial_elevation")


def add_vehicle_args(p) -> None:
    """The vehicle's flags (run, render, sweep, demo)."""
    add_spec_flags(p, "imu", "station_keeping", "imu_noise", "station_keeping_gains",
                   "mission", "node_error")


def add_head_args(p) -> None:
    """The receiver's gimbal and photodiodes (run, render, sweep, demo)."""
    add_spec_flags(p, "gimbal", "receiver", "channel_mismatch", "lens_field_deg")


def add_loop_args(p) -> None:
    add_spec_flags(p, "scenario", "estimator", "disturbances", "filter_distance",
                   "supervision")
    add_vehicle_args(p)
    add_world_args(p)
    add_head_args(p)
