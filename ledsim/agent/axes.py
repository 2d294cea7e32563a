"""The gimbal's axes in the agent: one number per axis, a float for the paper's one.

Every angle, rate, input u and torque the agent handles is a value over the layout's
axes (:attr:`~ledsim.physics.layout.ReceiverLayout.axes`): an array of shape
(n_axes,), and for the paper's one axis a float, which is the same array of one at a
fraction of its cost (numpy spends about a microsecond on each operation of a small
array; the step makes dozens). The helpers here take either, and give back the kind
they were given, so each law, motor and slew is written once for both.

An estimate over n axes is the state (angle_1 .. angle_n, rate_1 .. rate_n): the paper's
(phi, phidot) for n = 1, and (azimuth, elevation, their rates) for a pan-tilt head.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["angles_rates", "as_axes", "clip", "magnitude"]


def clip(x, lo, hi):
    """``x`` within [lo, hi]: a float for a float (``min``/``max``, as the paper's one
    axis always did, to the last bit), else per axis over an array."""
    if isinstance(x, np.ndarray):  # np.clip's numbers, without its wrapper's cost
        return np.minimum(np.maximum(x, lo), hi)
    return min(max(x, lo), hi)


def magnitude(x) -> float:
    """The largest |x| over the axes [the value's unit] (|x| for one axis)."""
    if not isinstance(x, np.ndarray):
        return abs(float(x))
    # np.max(np.abs(x)) in plain floats (NaN wins, as there): numpy's calls cost 5 us
    values = [abs(v) for v in x.ravel().tolist()]
    return math.nan if any(v != v for v in values) else max(values)


def angles_rates(xhat):
    """An estimate's angles and rates: ``(xhat[0], xhat[1])`` for one axis (numpy
    floats), else the two halves ``(xhat[:n], xhat[n:])``, each shape (n,)."""
    if len(xhat) == 2:
        return xhat[0], xhat[1]
    n = len(xhat) // 2
    return xhat[:n], xhat[n:]


def as_axes(value, n: int):
    """``value`` over ``n`` axes: a float for one axis, else an array of shape (n,) (a
    float is broadcast to every axis). Raises ``ValueError`` naming a wrong length."""
    if n == 1:
        a = np.asarray(value, dtype=float).reshape(-1)
        if a.size != 1:
            raise ValueError(f"{value!r} has {a.size} values for a gimbal of one axis")
        return float(a[0])
    a = np.broadcast_to(np.asarray(value, dtype=float), (n,)) if np.ndim(value) == 0 \
        else np.asarray(value, dtype=float)
    if a.shape != (n,):
        raise ValueError(f"{value!r} has shape {a.shape} for a gimbal of {n} axes: "
                         f"give one per axis, shape ({n},)")
    return a.copy()
