"""Estimation, grouped by what it estimates: :mod:`observer.kkl` (the learned KKL family),
:mod:`observer.baselines` (the EKF, UKF, particle filter and oracle),
:mod:`observer.navigation` (the vehicle's own state) and :mod:`observer.supervision` (is
the estimate still right). At the top: the system interface, the estimator's shape, the
noise, metrics, the PCRB, recordings, and the row kernels many worlds share.

This package never imports :mod:`ledsim`; plants reach it through
:class:`observer.system.DiscreteSystem`.
"""

import importlib

import observer.moved  # noqa: F401  (old module paths stay importable)

# Imported on first use (numpy stays unloaded until needed; see ledsim.cli.main).
_LAZY = {"DiscreteSystem": ".system", "Estimator": ".estimator", "KKLDesign": ".kkl.fixed_gain",
         "KKLObserver": ".kkl.fixed_gain"}
__all__ = list(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module 'observer' has no attribute {name!r}")
