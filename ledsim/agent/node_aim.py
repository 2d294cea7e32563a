"""A pan-tilt supervisor's use of the navigation's cue on the move: where to look, how
fast the node turns, and which fixes and estimates are too far from it to be the LED.

The cue (:mod:`ledsim.agent.node_cue`) is told anew each step, in the supervisor's
inertial encoder angles. While acquiring, the head slews to the fixes' target, moved as
the cue has moved since it was set; otherwise (before the LED is seen, after a loss) it
looks at the cue itself: the last estimate before a loss is the least sure of all.
"""

from __future__ import annotations

import numpy as np

from ledsim.agent.axes import magnitude

#: The time constant of the low-pass on the cue's turn rate [s] (the navigation's
#: position jitters one step's difference by 0.1 rad/s at 5 m).
CUE_RATE_TIME = 0.3
#: A fix or an estimate farther than this from where the navigation puts the node is
#: not the LED [rad] (the hull shading part of the quad as a fly-by's node falls behind
#: fixed the beam 1.8 rad off; a beam's edge at a few noise deviations sent the KKL's
#: estimate 0.9 rad off; the navigation's error is 1 m at worst, 0.2 rad at 5 m).
CUE_GATE = 0.35


class NodeAim:
    """The cue, its turn rate, and where it was when the supervisor's target was set.

    Args:
        Te: the control period [s].
    """

    def __init__(self, Te: float):
        self.Te = Te
        self.cue: np.ndarray | None = None  # told each step (None: a station)
        self._last: np.ndarray | None = None  # the last step's cue
        self.rate: np.ndarray | None = None  # its turn [rad/s] (None: no cue)
        self._seen: np.ndarray | None = None  # the cue when the target was set
        self.spread = 0.0  # the node's uncertainty [rad] (NodeView.spread)

    def tell(self, cue: np.ndarray, spread: float = 0.0) -> None:
        """Where the navigation puts the node this step [rad], and how unsure it is of
        it [rad] (it widens the gate)."""
        self.cue, self.spread = cue, spread

    def observe(self) -> None:
        """At the start of a step: the cue's turn, low-passed, when it was told anew."""
        if self.cue is None or self.cue is self._last:
            return
        if self._last is None:
            self.rate = np.zeros(2)
        else:
            a = self.Te / CUE_RATE_TIME
            self.rate += a * ((self.cue - self._last) / self.Te - self.rate)
        self._last = self.cue

    def target_set(self) -> None:
        """The supervisor's target was set now."""
        self._seen = None if self.cue is None else self.cue.copy()

    def aim(self, target: np.ndarray | None, acquiring: bool) -> np.ndarray | None:
        """Where to look [rad] (module doc); without a cue, ``target``."""
        if self.cue is None:
            return target
        if not acquiring or target is None or self._seen is None:
            return self.cue
        aim = target + (self.cue - self._seen)
        return self.cue if self.off(aim) else aim

    def off(self, where: np.ndarray) -> bool:
        """Whether encoder angles ``where`` [rad] are farther than :data:`CUE_GATE`
        and the node's :attr:`spread` from the cue (False without one)."""
        return self.cue is not None and magnitude(where - self.cue) > CUE_GATE + self.spread

    def settled(self, qdot: np.ndarray, arrive_rate: float) -> bool:
        """The head turns no faster than ``arrive_rate`` [rad/s] against the cue's turn
        (a fly-by's closest approach turns the node at 0.3 rad/s of pan)."""
        rate = qdot if self.rate is None else qdot - self.rate
        return magnitude(rate) <= arrive_rate
