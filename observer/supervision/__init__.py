"""Supervising any estimator of the link: the consistency monitor
(:mod:`~observer.supervision.monitor`), the link's gain, the gimbal's unexplained load, a
fading channel, and the estimate carried through an occlusion."""

from observer.moved import lent_names

# alias: this package took the path of the old module observer/supervision.py
__getattr__ = lent_names("observer.supervision.monitor")
