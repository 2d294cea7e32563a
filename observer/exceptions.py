"""Errors of the estimation package (it does not import :mod:`ledsim`)."""


class ObserverError(ValueError):
    """A checkpoint, design or training setting that cannot be used as asked."""
