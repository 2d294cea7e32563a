"""Rotations in three dimensions: the cross-product matrix, and the exponential and
logarithm maps between rotation vectors (axis times angle) [rad] and matrices.

Each takes one vector (3,) or matrix (3, 3), or a stack of them (N, 3) or (N, 3, 3),
and computes every row the same way: a row's result does not depend on the stack it is
in. The transcendental functions of one angle are libm's (``math``), as numpy's own
SIMD ``arccos`` can differ from it in the last bit.
"""

from __future__ import annotations

import math
from itertools import repeat

import numpy as np

__all__ = ["skew", "rotation_exp", "rotation_log", "per_element", "libm_square"]


def per_element(f, *args) -> np.ndarray:
    """``f`` (a ``math`` function) of each element of the arrays ``args`` (one shape; a
    float argument stands for every element)."""
    arrays = [a if isinstance(a, np.ndarray) else np.asarray(a, dtype=float)
              for a in args if type(a) is not float]
    shape = arrays[0].shape
    if arrays[0].size == 1:  # one vehicle: no lists to build
        return np.array([f(*(a if type(a) is float else float(a.flat[0]) for a in args))]
                        ).reshape(shape)
    out = np.array(list(map(f, *(repeat(a) if type(a) is float else a.ravel().tolist()
                                 for a in args))))
    return out if len(shape) == 1 else out.reshape(shape)


def libm_square(x) -> np.ndarray:
    """x ** 2 of each element as a float's ``** 2`` computes it (libm's ``pow``, which
    differs from x * x, numpy's square, in the last bit of about 1 in 1000)."""
    x = x if isinstance(x, np.ndarray) else np.asarray(x, dtype=float)
    out = np.array([v**2 for v in x.ravel().tolist()])
    return out if x.ndim == 1 else out.reshape(x.shape)


# [a]x's nine entries as signs times the components of a (row-major).
_SKEW_INDEX = np.array([0, 2, 1, 2, 0, 0, 1, 0, 0])
_SKEW_SIGN = np.array([0.0, -1.0, 1.0, 1.0, 0.0, -1.0, -1.0, 1.0, 0.0])


def skew(a) -> np.ndarray:
    """[a]x, the matrix of the cross product a x . ((..., 3) -> (..., 3, 3))."""
    a = np.asarray(a, dtype=float)
    return (a[..., _SKEW_INDEX] * _SKEW_SIGN).reshape(a.shape[:-1] + (3, 3))


def rotation_exp(phi) -> np.ndarray:
    """Exp(phi): the rotation matrix of the rotation vector ``phi`` [rad] (Rodrigues);
    (..., 3) -> (..., 3, 3)."""
    phi = np.asarray(phi, dtype=float)
    if phi.size == 3:  # one vector: Rodrigues in floats (the same operations)
        return _exp_one(phi.reshape(3)).reshape(phi.shape[:-1] + (3, 3))
    sq = libm_square(phi)
    angle = np.sqrt(sq[..., 0] + sq[..., 1] + sq[..., 2])[..., None, None]
    K = skew(phi)
    small = angle < 1e-9
    if small.all():
        return np.eye(3) + K + 0.5 * K @ K
    safe = np.where(small, 1.0, angle) if small.any() else angle
    big = np.eye(3) + (np.sin(safe) / safe) * K \
        + ((1.0 - np.cos(safe)) / libm_square(safe)) * K @ K
    return np.where(small, np.eye(3) + K + 0.5 * K @ K, big) if small.any() else big


def rotation_log(R: np.ndarray) -> np.ndarray:
    """The rotation vector (axis times angle) [rad] of a rotation matrix;
    (..., 3, 3) -> (..., 3)."""
    R = np.asarray(R, dtype=float)
    if R.size == 9:  # one matrix: in floats (the same operations)
        return _log_one(R.reshape(3, 3)).reshape(R.shape[:-2] + (3,))
    trace = R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2]
    angle = per_element(math.acos, np.maximum(-1.0, np.minimum(1.0, 0.5 * (trace - 1.0))))
    angle = angle[..., None]
    flat = R.reshape(R.shape[:-2] + (9,))
    axis = flat[..., [7, 2, 3]] - flat[..., [5, 6, 1]]
    small = angle < 1e-9
    if small.all():
        return 0.5 * axis
    safe = np.where(small, 1.0, angle) if small.any() else angle
    big = axis * safe / (2.0 * np.sin(safe))
    return np.where(small, 0.5 * axis, big) if small.any() else big


_EYE = np.eye(3)
_EYE.flags.writeable = False


def _exp_one(phi: np.ndarray) -> np.ndarray:
    angle = math.sqrt(float(phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2))
    # skew(phi) from floats: the same products by the signs (0.0 keeps a zero's sign).
    x, y, z = phi.tolist()
    K = np.array([[x * 0.0, z * -1.0, y], [z, x * 0.0, x * -1.0], [y * -1.0, x, x * 0.0]])
    if angle < 1e-9:
        return _EYE + K + 0.5 * K @ K
    return _EYE + (math.sin(angle) / angle) * K \
        + ((1.0 - math.cos(angle)) / angle**2) * K @ K


def _log_one(R: np.ndarray) -> np.ndarray:
    angle = math.acos(max(-1.0, min(1.0, 0.5 * (float(R[0, 0] + R[1, 1] + R[2, 2]) - 1.0))))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-9:
        return 0.5 * axis
    return axis * angle / (2.0 * math.sin(angle))
