"""A long run window by window (a minute, say): does the link last, does the estimate,
and does the hull?

Per window of a run: the link's availability and FEC share, the mean power, the phi
estimate's RMSE, the share flagged lost, the silent errors, the losses declared (and the
false ones) and the re-seeds, the hull's horizontal distance from its station and the
navigation's horizontal error. A run whose navigation drifts, or whose estimate goes
wrong now and then, shows it here long before its whole-run averages move.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ledsim.files.results import DictAccess
from ledsim.loop.losses import StepFlags
from ledsim.loop.run_metrics import availability_mask
from ledsim.radiometry.data_channel import BIT_RATE, link_budget_of
from observer.noise import MeasurementNoise


@dataclass
class WindowMetrics(DictAccess):
    """One window of a run.

    Attributes:
        start, end: the window [s].
        availability: share of its steps with the link available (as
            :class:`~ledsim.loop.run_metrics.RunMetrics`) [-].
        fec_share: share of its steps under the FEC limit [-].
        mean_power: mean noise-free P1 [W].
        hull_error_rms: the hull's horizontal distance from its station, RMS [m]
            (None: no vehicle).
        navigation_error_rms: the navigation's horizontal error, RMS [m] (None: no
            vehicle).
        rmse_x1: RMSE of the reported estimate of phi [rad]; lost_share,
            silent_error_share: shares of its steps flagged lost, and wrong but not
            flagged after the warm-up [-]; loss_events, false_loss_events, reseeds: the
            losses declared in it, the false ones, and the estimator's restarts [-] (as
            :class:`~ledsim.loop.run_metrics.RunMetrics`; None: not measured).
    """

    start: float
    end: float
    availability: float
    fec_share: float
    mean_power: float
    hull_error_rms: float | None = None
    navigation_error_rms: float | None = None
    rmse_x1: float | None = None
    lost_share: float | None = None
    silent_error_share: float | None = None
    loss_events: int | None = None
    false_loss_events: int | None = None
    reseeds: int | None = None


def horizontal_rms(a: np.ndarray, b: np.ndarray) -> float:
    """RMS of the horizontal distance between the rows of ``a`` (N, >= 2) and those of
    ``b`` (N, >= 2), or the one point ``b`` (>= 2,) [m]."""
    d = np.asarray(a)[:, :2] - np.asarray(b)[..., :2]
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1)))) if len(d) else float("nan")


def window_metrics(p1: np.ndarray, power_max: np.ndarray, noise_std: float, Te: float,
                   window: float, hull: np.ndarray | None = None,
                   station: np.ndarray | None = None,
                   navigated: np.ndarray | None = None, *,
                   noise: MeasurementNoise | None = None, bit_rate: float = BIT_RATE,
                   steps: StepFlags | None = None) -> list[WindowMetrics]:
    """The run in windows of ``window`` [s] (the last one may be shorter; a run shorter
    than a window is one window), from photodiode 1's noise-free power ``p1`` and the
    most it could receive ``power_max`` (N,) [W], the sensor noise [W] and the period
    Te [s]; with a vehicle, the true hull position ``hull`` (N, 3) [m], its ``station``
    (3,) [m] and the ``navigated`` position (N, 3) [m]. ``noise``: the run's noise
    object (its link budget; None: ``noise_std``'s) at ``bit_rate`` [bit/s]; ``steps``:
    what each step was (:func:`~ledsim.loop.run_metrics.step_flags`; None: the estimate's
    metrics are not given)."""
    if not window > 0:
        raise ValueError(f"window={window!r} is not allowed: must be > 0 s")
    noise = MeasurementNoise(noise_std) if noise is None else noise
    n = len(p1)
    size = max(1, int(round(window / Te)))
    available, _ = availability_mask(p1, power_max, noise_std)
    vehicle = hull is not None and station is not None
    out = []
    for a in range(0, n, size):
        b = min(n, a + size)
        if out and b - a < size // 2:  # a short tail joins the last window
            break
        if b < n and n - b < size // 2:
            b = n
        budget = link_budget_of(p1[a:b], noise, Te, bit_rate)
        out.append(WindowMetrics(
            a * Te, b * Te, float(np.mean(available[a:b])), budget.fec_share,
            float(np.mean(p1[a:b])),
            horizontal_rms(hull[a:b], station[a:b] if np.ndim(station) == 2 else station)
            if vehicle else None,
            horizontal_rms(navigated[a:b], hull[a:b])
            if vehicle and navigated is not None else None,
            **({} if steps is None else _estimate_metrics(steps, a, b))))
    return out


def _estimate_metrics(steps: StepFlags, a: int, b: int) -> dict:
    """The estimate's metrics of steps ``a``..``b-1``."""
    counted = steps.counted[a:b]
    return {"rmse_x1": float(np.sqrt(np.mean(steps.error[a:b] ** 2))),
            "lost_share": float(np.mean(steps.lost[a:b])),
            "silent_error_share": float(np.mean(steps.silent[a:b][counted]))
            if counted.any() else 0.0,
            "loss_events": int(steps.onset[a:b].sum()),
            "false_loss_events": int(steps.false_onset[a:b].sum()),
            "reseeds": int(steps.reseeded[a:b].sum())}
