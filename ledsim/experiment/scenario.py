"""One scenario type for both worlds: initial state, control law, length, windows.

The closed-form registry (:data:`ledsim.paper.scenarios.PAPER_SCENARIOS`) and the MuJoCo
one (:data:`ledsim.loop.run_config.PHYSICS_SCENARIOS`) hold instances of :class:`Scenario`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ledsim.agent.laws import ControlLaw
from ledsim.constants import LinkConstants


@dataclass(frozen=True)
class Scenario:
    """One experiment.

    Attributes:
        name: registry key.
        x0: true initial state (phi [rad], phidot [rad/s]).
        law: control law template (``law.start(constants)`` gives the running copy).
        seconds: length of a run [s].
        steady_from: start of the steady-state window [s] (after the observer transient).
        warmup: time at the start without command [s], while the estimators forget
            their initial guess (in MuJoCo the motor then holds its encoder angle).
        description: one line for ``--help`` and tables.
    """

    name: str
    x0: tuple[float, float]
    law: ControlLaw
    seconds: float
    steady_from: float
    warmup: float = 0.0
    description: str = ""

    def n_steps(self, Te: float) -> int:
        """Control steps in a run."""
        return int(round(self.seconds / Te))

    def steady_step(self, Te: float) -> int:
        """First step of the steady-state window."""
        return int(round(self.steady_from / Te))

    def start_law(self, constants: LinkConstants) -> ControlLaw:
        return self.law.start(constants)
