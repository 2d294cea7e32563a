"""An underwater LED optical link in MuJoCo, kept aligned by a learned KKL observer.

Packages: :mod:`ledsim.paper` (the paper's closed-form model, scenarios and tables),
:mod:`ledsim.physics` (the MuJoCo world), :mod:`ledsim.loop` (the closed loop in
physics); shared: :mod:`ledsim.config` (constants), :mod:`ledsim.optics`,
:mod:`ledsim.control`, :mod:`ledsim.scenario`, :mod:`ledsim.estimators`.
"""

from .config import LinkConstants, ReceiverResponse
from .errors import LedsimError
from .paper.model import LEDLinkModel

__version__ = "0.2.0"

__all__ = ["LinkConstants", "ReceiverResponse", "LEDLinkModel", "LedsimError", "__version__"]
