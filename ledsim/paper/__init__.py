"""The paper's closed-form world: the model of section 2, the scenarios and tables of
section 4, and the Monte-Carlo evaluation behind ``ledsim evaluate``. Never imports
mujoco (``tests/test_layout.py`` checks)."""

from ledsim.paper.model import LEDLinkModel
from ledsim.paper.scenarios import PAPER_SCENARIOS, Noise, get_scenario, run

__all__ = ["LEDLinkModel", "PAPER_SCENARIOS", "Noise", "get_scenario", "run"]
