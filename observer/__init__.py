"""Estimation: system interface, learned KKL observer, its training, baselines, metrics.

This package never imports :mod:`ledsim`; plants reach it through
:class:`observer.system.DiscreteSystem`.
"""

import importlib

# Imported on first use (numpy stays unloaded until needed; see ledsim.cli.main).
_LAZY = {"DiscreteSystem": ".system", "Estimator": ".estimator", "KKLDesign": ".kkl",
         "KKLObserver": ".kkl"}
__all__ = list(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module 'observer' has no attribute {name!r}")
