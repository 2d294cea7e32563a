"""The filters' model at the range the navigation knows: a moving vehicle's link gain.

A pan-tilt's EKF, UKF and PF compute with the head's model, whose power gain is the
link's at the configured distance. A vehicle that flies a mission (``--mission``)
closes or opens the range: at 10 m of a link configured at 30 m, luma's powers are 9
times the model's, which the filters read as pointing (a 0.08 rad steady error in a
docking approach). :class:`RangeGain` moves the model's gain with the range the
vehicle's navigation puts the LED at, by the power law's factor

    g(r) = g(d) (d / r)^2 exp(-b (r - d))

(``ledsim/radiometry/optics.py:transmitter_gain``), and, where the navigation knows the
node's LED (a mission scenario's surveyed node: ``agent/node_cue.py``), by its
Lambertian factor cos(theta)^m / cos(theta_0)^m at the emission angle theta it sees the
vehicle at (a fly-by's node points its LED at the track's nearest point: 84 deg off it
at the start). The KKL of the pan-tilt reads ratios, which no gain changes.
"""

from __future__ import annotations

import math

#: The smallest cosine of the emission angle the factor takes [-] (past 89.4 deg the
#: LED is dark: its factor is floored, not zero, so the model stays invertible).
MIN_COS = 0.01


class RangeGain:
    """Tell a head model (:class:`~ledsim.physics.head_model.HeadModel`, a run's own
    copy) the gain at each step's range.

    Args:
        model: the model the filters compute with (its own: its gain is changed; None:
            only :meth:`factor`, for the supervisor's levels).
        distance: the configured distance d its gain is at [m].
        attenuation: the power law's b [1/m].
        theta: the emission angle the model's gain is at [rad].
        order: the LED's Lambertian order m [-].
    """

    def __init__(self, model, distance: float, attenuation: float, theta: float = 0.0,
                 order: float = 1.0):
        self.model, self.distance, self.attenuation = model, float(distance), attenuation
        self.base = None if model is None else float(model.power_gain)
        self.order = float(order)
        self.cos0 = max(math.cos(theta), MIN_COS)

    def anchor(self, r: float, theta: float) -> None:
        """The model's gain is the one at range ``r`` [m] and emission angle ``theta``
        [rad] (the node as the navigation saw it at the start)."""
        self.distance, self.cos0 = float(r), max(math.cos(theta), MIN_COS)

    def factor(self, r: float, theta: float | None = None) -> float:
        """The gain at range ``r`` [m] (and emission angle ``theta`` [rad]; None: the
        model's) over the model's [-]."""
        d, r = self.distance, max(float(r), 0.5)  # a mission keeps 1 m off the LED
        out = (d / r) ** 2 * math.exp(-self.attenuation * (r - d))
        if theta is not None:
            out *= (max(math.cos(theta), MIN_COS) / self.cos0) ** self.order
        return out

    def tell(self, r: float, theta: float | None = None) -> float:
        """The range is ``r`` [m] now (the emission angle ``theta`` [rad], when known);
        returns :meth:`factor`."""
        f = self.factor(r, theta)
        if self.model is not None:
            self.model.set_power_gain(self.base * f)
        return f
