"""What a closed-loop run is judged by: estimation error, alignment, link availability."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from observer.metrics import rmse

from ..config import LinkConstants
from ..control import intensity_maximum
from ..optics import peak_power
from ..results import DictAccess

ALIGN_TOLERANCE = math.radians(1.0)  # |phi - phi_ref| below this counts as aligned [rad]
AVAILABILITY_LEVEL = 0.9  # the link is available while P1 >= 90% of its maximum


@dataclass
class RunMetrics(DictAccess):
    """Metrics of one run.

    Attributes:
        rmse, rmse_steady: RMSE of (x1 [rad], x2 [rad/s]) over the run and from the
            scenario's steady-state start, keyed ``x1``, ``x2``.
        alignment_time: first time |phi - phi_ref| < 1 deg for 0.5 s [s] (None: never).
        availability: share of the run with P1 >= 90% of its maximum [-].
        mean_power: mean noise-free P1 [W].
        recovery_time: after a transient event (an occlusion) ends, time until aligned
            again [s]; None without such an event or without recovery.
    """

    rmse: dict
    rmse_steady: dict
    alignment_time: float | None
    availability: float
    mean_power: float
    recovery_time: float | None


def first_settled(flags: np.ndarray, Te: float, hold: float = 0.5) -> float | None:
    """First time [s] from which ``flags`` stays true for ``hold`` s (None: never)."""
    n_hold = int(round(hold / Te))
    ok = np.asarray(flags, dtype=bool)
    if len(ok) < n_hold:
        return None
    run = np.convolve(ok.astype(int), np.ones(n_hold, dtype=int), mode="valid")
    idx = np.flatnonzero(run == n_hold)
    return None if idx.size == 0 else float(idx[0] * Te)


def run_metrics(x: np.ndarray, xhat: np.ndarray, power_clean: np.ndarray, steady_from: float,
                constants: LinkConstants, event_end: float | None = None) -> RunMetrics:
    """Metrics of one run from its true state, estimate and noise-free powers.

    Args:
        x, xhat: true and estimated state, shape (N, 2) [rad, rad/s].
        power_clean: noise-free powers, shape (N, 2) [W].
        steady_from: start of the steady-state window [s].
        constants: the link (for the alignment target and the peak power).
        event_end: end of a transient event [s] for the recovery time.
    """
    Te = constants.Te
    e = rmse(xhat, x)
    es = rmse(xhat, x, int(round(steady_from / Te)))
    aligned = np.abs(x[:, 0] - intensity_maximum(constants)) < ALIGN_TOLERANCE
    p1 = power_clean[:, 0]
    recovery = None
    if event_end is not None:
        recovery = first_settled(aligned[int(round(event_end / Te)):], Te)
    return RunMetrics(
        rmse={"x1": float(e[0]), "x2": float(e[1])},
        rmse_steady={"x1": float(es[0]), "x2": float(es[1])},
        alignment_time=first_settled(aligned, Te),
        availability=float(np.mean(p1 >= AVAILABILITY_LEVEL * peak_power(constants))),
        mean_power=float(np.mean(p1)),
        recovery_time=recovery)
