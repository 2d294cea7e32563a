"""The gain tracker of a link: its model's gain, its deadband, and the receiver's shape
inversions (:class:`~observer.supervision.gain_tracking.GainTracker` in the loop's terms)."""

from __future__ import annotations

import numpy as np

from ledsim.constants import LinkConstants
from ledsim.radiometry.optics import (
    layout_power,
    nominal_noise_std,
    pair_phi_variance,
    pair_shape_inverse,
    pair_shape_numbers,
    peak_power,
)
from observer.supervision.gain_tracking import GainTracker


def model_gain(model, constants: LinkConstants) -> float:
    """Transmitter gain [W] of a model whose ``h`` is gain x [g(phi), g(phi + dphi)]
    (least squares over its domain)."""
    phi = np.linspace(model.domain_low[0], model.domain_high[0], 101)
    h = np.asarray(model.h(np.stack([phi, np.zeros_like(phi)], axis=-1)))
    g = layout_power(1.0, phi, constants)
    return float(np.sum(h * g) / np.sum(g * g))


#: The gain tracker's deadband on the bench, whose pointing samples carry 3.2 % noise
#: (``observer.supervision.gain_tracking.GainTracker``) [-].
BENCH_DEADBAND = 0.005


def tracker_deadband(constants: LinkConstants) -> float:
    """The gain tracker's deadband for a run of ``constants`` [-]: the bench's, or on a
    physical link the bench's scaled by the pointing samples' relative noise over the
    bench's (0.0007-0.02 % at luma's 6-60 m: the gain is that much better
    determined).
    ``docs/link_floor.md`` measures the bench's band, a tenth and a hundredth of it."""
    if constants.link is None:
        return BENCH_DEADBAND
    bench = LinkConstants()
    relative = nominal_noise_std(constants) / peak_power(constants)
    return BENCH_DEADBAND * min(1.0, relative / (bench.measurement_noise_std
                                                 / peak_power(bench)))


def link_gain_tracker(model, constants: LinkConstants, ratio: float = 1.0) -> GainTracker:
    """The gain tracker of a run of ``constants`` whose estimator's model is ``model``,
    starting from the gain ``ratio`` times the model's [-]."""
    band = tracker_deadband(constants)
    return GainTracker(model, lambda y: pair_shape_inverse(y, constants),
                       model_gain(model, constants), ratio=ratio, deadband=band,
                       deadband_moving=band,
                       phi_variance=lambda phi, y, sigma: pair_phi_variance(
                           phi, y, sigma, constants), shape=pair_shape_numbers(constants))
