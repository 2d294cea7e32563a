"""Rotations in three dimensions: the cross-product matrix, and the exponential and
logarithm maps between rotation vectors (axis times angle) [rad] and matrices."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["skew", "rotation_exp", "rotation_log"]


def skew(a) -> np.ndarray:
    """[a]x, the matrix of the cross product a x . (3x3)."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def rotation_exp(phi) -> np.ndarray:
    """Exp(phi): the rotation matrix of the rotation vector ``phi`` [rad] (Rodrigues)."""
    angle = math.sqrt(float(phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2))
    K = skew(phi)
    if angle < 1e-9:
        return np.eye(3) + K + 0.5 * K @ K
    return np.eye(3) + (math.sin(angle) / angle) * K \
        + ((1.0 - math.cos(angle)) / angle**2) * K @ K


def rotation_log(R: np.ndarray) -> np.ndarray:
    """The rotation vector (axis times angle) [rad] of a rotation matrix."""
    angle = math.acos(max(-1.0, min(1.0, 0.5 * (np.trace(R) - 1.0))))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-9:
        return 0.5 * axis
    return axis * angle / (2.0 * math.sin(angle))
