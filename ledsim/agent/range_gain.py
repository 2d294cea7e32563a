"""The filters' model at the range the navigation knows: a moving vehicle's link gain.

A pan-tilt's EKF, UKF and PF compute with the head's model, whose power gain is the
link's at the configured distance. A vehicle that flies a mission (``--mission``)
closes or opens the range: at 10 m of a link configured at 30 m, luma's powers are 9
times the model's, which the filters read as pointing (a 0.08 rad steady error in a
docking approach). :class:`RangeGain` moves the model's gain with the range the
vehicle's navigation puts the LED at, by the power law's factor

    g(r) = g(d) (d / r)^2 exp(-b (r - d))

(``ledsim/radiometry/optics.py:transmitter_gain``: the LED's angle is left as the
start's). The KKL of the pan-tilt reads ratios, which no gain changes.
"""

from __future__ import annotations

import math


class RangeGain:
    """Tell a head model (:class:`~ledsim.physics.head_model.HeadModel`, a run's own
    copy) the gain at each step's range.

    Args:
        model: the model the filters compute with (its own: its gain is changed).
        distance: the configured distance d its gain is at [m].
        attenuation: the power law's b [1/m].
    """

    def __init__(self, model, distance: float, attenuation: float):
        self.model, self.distance, self.attenuation = model, float(distance), attenuation
        self.base = float(model.power_gain)

    def tell(self, r: float) -> None:
        """The range is ``r`` [m] now."""
        d, r = self.distance, max(float(r), 0.5)  # a mission keeps 1 m off the LED
        self.model.set_power_gain(self.base * (d / r) ** 2 *
                                  math.exp(-self.attenuation * (r - d)))
