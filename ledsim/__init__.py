"""An underwater LED optical link in MuJoCo, kept aligned by a learned KKL observer.

The plant: :mod:`ledsim.physics` (the MuJoCo world: scene, sensors, water, disturbances)
and :mod:`ledsim.radiometry` (optics, water's attenuation, link presets and budgets).
The agent: :mod:`ledsim.agent` (the control step, supervision, acquisition, control
laws, the vehicle's autopilot). The experiments: :mod:`ledsim.paper` (the paper's
closed-form model and tables), :mod:`ledsim.loop` (runs in MuJoCo), :mod:`ledsim.envs`
(Gymnasium), :mod:`ledsim.cli`, and what they share, :mod:`ledsim.experiment`.
Estimation is :mod:`observer`'s. :mod:`ledsim.constants` holds the physical constants.
"""

import importlib

import ledsim.moved  # noqa: F401  (old module paths stay importable)

__version__ = "0.2.0"

# Imported on first use, so that the command line can pin BLAS threads before numpy loads.
_LAZY = {"LinkConstants": ".constants", "ReceiverResponse": ".constants",
         "LEDLinkModel": ".paper.model", "LedsimError": ".errors"}
__all__ = [*_LAZY, "__version__"]


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module 'ledsim' has no attribute {name!r}")
