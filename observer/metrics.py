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


def pointing_loss_db(allowed, received, mask=None) -> float:
    """The mean pointing loss [dB]: 10 log10 of the power the geometry allows over the
    power received, each summed over the steps in ``mask`` (None: all), so a deep fade
    weighs by the power it lost rather than by its decibels. 0 for a perfect pointing;
    inf when nothing was received; NaN without a step."""
    a, r = np.asarray(allowed, dtype=float), np.asarray(received, dtype=float)
    if mask is not None:
        a, r = a[mask], r[mask]
    if a.size == 0:
        return float("nan")
    total = float(np.sum(r))
    return float("inf") if total <= 0 else float(10.0 * np.log10(np.sum(a) / total))
