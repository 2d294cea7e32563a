"""The range a run's path spans, and where along it the receiver first saturates.

The range is the configured distance changed by the vehicle's mission (``--mission``)
and the transmitter's drift along the link (``transmitter:drift=V,drift_until=T``):
d(t) = d + sum of V min(t, T). A run whose range closes can reach the distance at which
the receiver's peak power fills its digitiser's scale, with the detector's gain turned
all the way down, from a start well outside it. Such a run is refused before it starts
(:func:`check_saturation`): the estimators' model does not clip. (Before the detectors'
gain control, bluecomm-200 in coastal water clipped from 9.0 m on, 42 s into a closing
from 30 m at 0.5 m/s; with it, no preset's bare detector clips down to 1 m.)
"""

from __future__ import annotations

import numpy as np

from ledsim.errors import LedsimError
from ledsim.physics.disturbances import TransmitterMotion, parse_disturbance
from ledsim.physics.scene import transmitter_rise
from ledsim.radiometry.link_presets import link_constants
from ledsim.radiometry.optics import receiver_saturates

#: The path's range is looked at every this many seconds [s].
PATH_STEP = 0.1


def range_path(cfg) -> tuple[np.ndarray, np.ndarray]:
    """(times [s], ranges [m]) of the run ``cfg``'s path, every :data:`PATH_STEP`: the
    mission's target (in the start frame, the LED ``distance`` ahead, as seen from the
    gimbal's hinge when the hull heads at it) and the transmitter's drift."""
    t = np.arange(0.0, cfg.run_seconds + PATH_STEP / 2, PATH_STEP)
    d = np.full(t.shape, float(cfg.distance))
    mission = cfg.mission_plan
    if mission is not None:
        from ledsim.agent.guidance import PathReference, led_in_start_frame

        where = PathReference(mission, (0.0, 0.0), 0.0).positions(t)
        rise = transmitter_rise(cfg.depth, cfg.transmitter_depth, cfg.distance)
        x, y = led_in_start_frame(cfg.distance, rise)
        d = np.sqrt((x - where[:, 0]) ** 2 + (y - where[:, 1]) ** 2 + rise ** 2)
    for spec in cfg.disturbances:
        dist = parse_disturbance(spec)
        if isinstance(dist, TransmitterMotion) and dist.drift:
            d += dist.drift * np.minimum(t, dist.drift_until)
    return t, d


def _saturates_at(cfg, distance: float) -> bool:
    c = link_constants(cfg.link, distance, cfg.water, cfg.attenuation,
                       lens_field=cfg.world.lens_field)
    return receiver_saturates(c, cfg.noise_scale)


def saturation_onset(cfg) -> tuple[float, float] | None:
    """(range [m], time [s]) at which the run's receiver first saturates along its path
    (:func:`~ledsim.radiometry.optics.receiver_saturates` at that range), or None when
    it never does. The receiver's peak power falls with the range, so the range where
    it starts is found by bisection between the path's nearest and farthest."""
    t, d = range_path(cfg)
    near = int(np.argmin(d))
    if not _saturates_at(cfg, float(d[near])):
        return None
    if _saturates_at(cfg, float(d[0])):
        return float(d[0]), 0.0
    lo = _threshold(cfg, float(d[near]), float(d[0]))
    first = int(np.argmax(d <= lo))
    return lo, float(t[first])


def _threshold(cfg, lo: float, hi: float) -> float:
    """The range [m] under which the receiver saturates, between ``lo`` (where it does)
    and ``hi`` (where it does not), by bisection (the peak power falls with range)."""
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _saturates_at(cfg, mid) else (lo, mid)
    return lo


def check_saturation(cfg) -> None:
    """Refuse a run whose receiver saturates anywhere along its path (at its distance,
    or where its mission or the transmitter's drift brings it), naming where: its peak
    power fills the digitiser's scale with the detector's gain turned all the way down
    (``Digitiser.saturation``), so the aligned samples clip, and the estimators, whose
    model has no clipping, would read a clipped set of powers as an angle off the
    peak."""
    onset = saturation_onset(cfg)
    if onset is None:
        return
    from ledsim.radiometry.optics import peak_power

    distance, t = onset
    # the range it must keep: where the saturation starts (beyond the start, if there)
    keep = _threshold(cfg, distance, 10.0 * distance + 10.0) if t == 0.0 else distance
    c = link_constants(cfg.link, distance, cfg.water, cfg.attenuation,
                       lens_field=cfg.world.lens_field)
    top = c.measurement_noise(cfg.noise_scale).digitiser.saturation
    where = f"at --distance {cfg.distance:g}" if t == 0.0 else \
        f"from {distance:.2f} m on, {t:.1f} s into the run (along its path)"
    raise LedsimError(f"the receiver of --link {cfg.link} saturates {where}: its peak "
                      f"power {peak_power(c):.3g} W fills its scale of {top:.3g} W (its "
                      f"detector's gain turned all the way down), so its samples would "
                      f"clip: keep the range over {keep:.2f} m")
