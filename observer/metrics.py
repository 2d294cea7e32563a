"""Error metrics shared by every scenario and table."""

from __future__ import annotations

import numpy as np


def rmse(estimate: np.ndarray, truth: np.ndarray, start: int = 0) -> np.ndarray:
    """Root-mean-square error over time (axis 0) from step ``start``, per component."""
    err = np.asarray(estimate, dtype=float)[start:] - np.asarray(truth, dtype=float)[start:]
    if err.shape[0] == 0 or not np.isfinite(err).any():
        return np.full(err.shape[1:], np.nan)  # empty window: undefined, not a warning
    return np.sqrt(np.nanmean(err**2, axis=0))


def converged(estimate: np.ndarray, truth: np.ndarray, start: int,
              tolerance: float = 0.02, component: int = 0) -> bool:
    """Whether the steady-state RMSE of one component (default x1) is below ``tolerance``."""
    return bool(rmse(estimate[:, component], truth[:, component], start) < tolerance)


def mean_and_spread(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and sample standard deviation over seeds (axis 0)."""
    values = np.asarray(values, dtype=float)
    spread = values.std(axis=0, ddof=1) if len(values) > 1 else np.zeros_like(values[0])
    return values.mean(axis=0), spread
