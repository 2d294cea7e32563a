"""What a run's head does not take, refused in one line: a pan-tilt's (the paper's bench,
an estimator it does not run, a checkpoint that is not a pair) and a lens's."""

from __future__ import annotations

from ledsim.errors import LedsimError, check_ranges
from ledsim.experiment.estimators import LOOP_KKL_ESTIMATORS as KKL_ON_BENCH
from ledsim.loop.registry import PAN_TILT_ESTIMATORS


def _check_lens(cfg) -> None:
    """A lens fits a physical receiver, narrower than its bare field; the yaw gimbal's
    shipped KKLs were trained for the bare detector."""
    check_ranges([("--lens-field-deg", cfg.lens_field_deg, 1.0 <= cfg.lens_field_deg < 30.0,
                   "in [1, 30) deg: narrower than the bare detector's 30 deg")])
    if cfg.link == "paper":
        raise LedsimError("--lens-field-deg is not allowed with --link paper: the bench's "
                          "photodiodes have no lens (choose a physical --link)")
    if not cfg.world.two_axes and cfg.estimator in KKL_ON_BENCH and not cfg.checkpoint:
        raise LedsimError(f"estimator {cfg.estimator!r} is not allowed with "
                          "--lens-field-deg on the yaw gimbal: its shipped KKLs were "
                          "trained for the bare 30 deg detector (use --gimbal pan-tilt, or "
                          "ekf, ukf, pf or oracle)")


def _check_two_axes(cfg) -> None:
    """What a pan-tilt run does not take (yet), refused in one line."""
    if cfg.link == "paper":
        raise LedsimError("--gimbal pan-tilt is not allowed with --link paper: the paper's "
                          "bench measures its photodiodes' response about the hinge alone, "
                          "so no photodiode sees the tilt (choose a physical --link)")
    if cfg.estimator not in PAN_TILT_ESTIMATORS:
        raise LedsimError(f"estimator {cfg.estimator!r} is not allowed with --gimbal "
                          f"pan-tilt: choose one of {', '.join(PAN_TILT_ESTIMATORS)}")
    if cfg.filter_distance != "configured":
        raise LedsimError(f"--filter-distance {cfg.filter_distance} is not allowed with "
                          "--gimbal pan-tilt: its filters know the configured distance")
    if cfg.checkpoint:
        from ledsim.files.resources import pair_paths

        if cfg.estimator != "kkl":
            raise LedsimError(f"--checkpoint is not allowed with --estimator "
                              f"{cfg.estimator} on a pan-tilt head: it is the KKL's pair")
        missing = [str(p) for p in pair_paths(cfg.checkpoint).values() if not p.is_file()]
        if missing:
            raise LedsimError(f"--checkpoint {cfg.checkpoint!r} on a pan-tilt head names a "
                              f"pair: {missing[0]!r} is missing (ledsim train --gimbal "
                              "pan-tilt --out NAME writes NAME_azimuth and NAME_elevation)")
