"""Estimation: system interface, learned KKL observer, its training, baselines, metrics.

This package never imports :mod:`ledsim`; plants reach it through
:class:`observer.system.DiscreteSystem`.
"""

from .estimator import Estimator
from .kkl import KKLDesign, KKLObserver
from .system import DiscreteSystem

__all__ = ["DiscreteSystem", "Estimator", "KKLDesign", "KKLObserver"]
