"""An underwater LED optical link in MuJoCo, kept aligned by a learned KKL observer.

Packages: :mod:`ledsim.paper` (the paper's closed-form model, scenarios and tables),
:mod:`ledsim.physics` (the MuJoCo world), :mod:`ledsim.loop` (the closed loop in
physics); shared: :mod:`ledsim.config` (constants), :mod:`ledsim.optics`,
:mod:`ledsim.control`, :mod:`ledsim.scenario`, :mod:`ledsim.estimators`.
"""

import importlib

__version__ = "0.2.0"

# Imported on first use, so that the command line can pin BLAS threads before numpy loads.
_LAZY = {"LinkConstants": ".config", "ReceiverResponse": ".config",
         "LEDLinkModel": ".paper.model", "LedsimError": ".errors"}
__all__ = [*_LAZY, "__version__"]


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module 'ledsim' has no attribute {name!r}")
