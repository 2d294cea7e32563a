"""Checks and notes a command makes before it runs: the vehicle's flags and scene, a
distance the shipped KKL does not serve, a receiver that saturates, and an LED out of
the one-axis gimbal's plane."""

from __future__ import annotations

import logging
from dataclasses import replace

from ledsim.errors import LedsimError

log = logging.getLogger("ledsim")


def _check_vehicle(cfg) -> None:
    """A user's scene without the vehicle's sensors: refused with the IMU on, and said
    once with ``--no-imu`` (the run then has no station keeping)."""
    if cfg.scene is None:
        return
    from ledsim.loop.validation import check_world

    ids = check_world(cfg.world_config())  # the validation's world, built once
    if ids.vehicle_sensors is not None:
        return
    if cfg.imu:
        missing = ids.missing_sensors
        raise LedsimError(f"the scene {cfg.scene} lacks the vehicle's sensor"
                          f"{'s' if len(missing) > 1 else ''} {', '.join(missing)}: run it "
                          "with --no-imu")
    log.warning(f"the scene {cfg.scene} has no vehicle sensors: no IMU and no station "
                "keeping (the hull drifts with the water)")


def _warn_unserved(cfg) -> None:
    """Say so when the shipped KKL runs at a distance it is not measured to serve, when
    the link is too weak for the minimum-time acquisition it asks for (a receiver that
    saturates is refused: ``loop/path_range.py:check_saturation``)."""
    from ledsim.loop.build.estimation import SERVED_DISTANCES, served
    from ledsim.loop.registry import PHYSICS_SCENARIOS

    _warn_out_of_plane(cfg)

    if not served(cfg):
        lo, hi = SERVED_DISTANCES
        log.warning(f"--distance {cfg.distance:g} is outside the {lo:g}-{hi:g} m the shipped "
                    "KKL is measured to serve: its results are not vouched for "
                    "(results.json: distance_served false)")
    if cfg.acquisition == "minimum-time" and cfg.supervision and \
            PHYSICS_SCENARIOS[cfg.scenario].law.tracks_beam and not cfg.fast_acquisition:
        log.warning("the link is too weak for the minimum-time acquisition's fix (peak "
                    "SNR under 3.5): this run acquires with the warm-up")


#: How far out of the gimbal's plane [deg] the LED may stand before a run says so.
OUT_OF_PLANE_NOTE = 5.0


def _warn_out_of_plane(cfg) -> None:
    """Say so when the LED stands more than :data:`OUT_OF_PLANE_NOTE` out of the yaw
    gimbal's plane (a ``--transmitter-depth`` unlike ``--depth``), with what it costs:
    the receiver's cone response at that elevation, which no pan angle recovers (the
    pointing loss of a perfect aim), and whether that leaves the availability any
    chance (P1 within ``AVAILABILITY_LEVEL`` of the geometry's best)."""
    import math

    from ledsim.loop.run_metrics import AVAILABILITY_LEVEL
    from ledsim.radiometry.optics import receiver_response

    if cfg.transmitter_depth is None or cfg.world.two_axes:  # a pan-tilt turns to it
        return
    c = cfg.world_config().constants
    if c.link is None:  # the bench measures only about the hinge
        return
    rise = cfg.depth - cfg.transmitter_depth  # the LED above the receiver [m]
    elevation = math.asin(max(-1.0, min(1.0, rise / cfg.distance)))
    if abs(math.degrees(elevation)) <= OUT_OF_PLANE_NOTE:
        return
    g = float(receiver_response(elevation, c.receiver) / receiver_response(0.0, c.receiver))
    loss = -10.0 * math.log10(max(g, 1e-300))
    floor = -10.0 * math.log10(AVAILABILITY_LEVEL)
    verdict = (f", more than the {floor:.2f} dB the availability allows (P1 within "
               f"{AVAILABILITY_LEVEL:.0%} of the best): expect an availability near 0"
               if loss > floor else "")
    log.warning(f"the LED stands {abs(math.degrees(elevation)):.1f} deg "
                f"{'above' if rise > 0 else 'below'} the yaw gimbal's plane "
                f"(--transmitter-depth {cfg.transmitter_depth:g} m, --depth {cfg.depth:g} m, "
                f"{cfg.distance:g} m apart), which the one-axis gimbal cannot turn to: "
                f"{loss:.2f} dB of pointing loss however well it aims{verdict}")


def _say_head(cfg, args) -> None:
    """One line when a physical-link run whose command line names no head runs the yaw
    gimbal, the pan-tilt default's exception (:func:`~ledsim.loop.registry.yaw_only`);
    a checkpoint's own error comes first."""
    from ledsim.loop.build.estimation import check_checkpoint
    from ledsim.loop.registry import PAN_TILT_ESTIMATORS, yaw_only

    if getattr(args, "gimbal", None) is not None or getattr(args, "receiver", None) \
            is not None or cfg.link == "paper" or cfg.world.head[0] != "yaw":
        return
    check_checkpoint(cfg)
    e = cfg.estimation
    why = yaw_only(e.estimator, e.checkpoint)
    log.info(f"runs the yaw gimbal with its pair, not a physical link's pan-tilt default: "
             f"{why} (--gimbal yaw says so; --gimbal pan-tilt takes "
             f"{', '.join(PAN_TILT_ESTIMATORS)})")


def _warn_mixed_heads(grid) -> None:
    """Say so when a sweep's estimators run on different heads: on a physical link a
    one-axis estimator turns the default head into the yaw, the others the pan-tilt."""
    heads = {}
    for est in grid.estimators:
        heads.setdefault(replace(grid.base, estimator=est).world.head[0], est)
    if len(heads) > 1:
        log.warning("the sweep's estimators run on different heads (" + ", ".join(
            f"{e} on the {g}" for g, e in sorted(heads.items())) + "): name --gimbal yaw "
            "to compare them on one")
