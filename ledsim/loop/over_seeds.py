"""What a run's summary gives over its seeds: a value's mean and spread
(:class:`Stat`), each window's metrics, and a pan-tilt run's errors per axis."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ledsim.files.results import DictAccess
from ledsim.loop.outcome import RunOutcome
from observer.metrics import mean_and_spread


@dataclass
class Stat(DictAccess):
    """Mean and sample standard deviation over the seeds that have a value, and how
    many did (``n``); ``mean`` is None when none did. NaN means undefined (an empty
    steady-state window in a short run) and counts as no value."""

    mean: float | None
    std: float | None
    n: int

    @classmethod
    def over(cls, values) -> Stat:
        vals = [v for v in values if v is not None and not math.isnan(v)]
        if not vals:
            return cls(None, None, 0)
        mean, spread = mean_and_spread(np.array(vals, dtype=float))
        return cls(float(mean), float(spread), len(vals))


#: The per-window metrics a summary gives over the seeds (:class:`WindowMetrics`).
WINDOW_KEYS = ("availability", "fec_share", "mean_power", "hull_error_rms",
               "navigation_error_rms", "rmse_x1", "lost_share", "silent_error_share",
               "loss_events", "false_loss_events", "reseeds")


def summarize_windows(outs: list[RunOutcome]) -> list[dict] | None:
    """Each window's metrics over the seeds (None: the runs have no windows)."""
    if not outs or outs[0].windows is None:
        return None
    return [{"start": w.start, "end": w.end,
             **{k: Stat.over(getattr(o.windows[j], k) for o in outs) for k in WINDOW_KEYS}}
            for j, w in enumerate(outs[0].windows)]


#: The RMSE a pan-tilt run gives per axis and in all (:class:`RunMetrics`'s keys).
AXIS_KEYS = ("azimuth", "elevation", "pointing")


def per_axis(outs: list[RunOutcome]) -> dict:
    """``rmse_azimuth``, ``rmse_elevation``, ``rmse_pointing`` [rad] and their steady
    ``rmse_steady_`` forms over the seeds, for a pan-tilt run (none on one axis)."""
    if not outs or "pointing" not in outs[0].metrics.rmse:
        return {}
    return {f"{name}_{k}": Stat.over(getattr(o.metrics, name)[k] for o in outs)
            for name in ("rmse", "rmse_steady") for k in AXIS_KEYS}


#: What a run delivered, per seed (:class:`~ledsim.radiometry.goodput.Goodput`).
DATA_KEYS = ("goodput_bits", "ideal_bits", "outages", "outage_s", "edge_goodput_bits",
             "edge_ideal_bits")


def data_delivered(outs: list[RunOutcome]) -> dict:
    """``goodput_bits``, ``ideal_bits`` [bit], ``outages`` and ``outage_s`` [s] over the
    seeds, and ``range_m``, the range's [nearest, farthest] over every seed [m]."""
    spans = [o.metrics.range_m for o in outs if o.metrics.range_m]
    return {**{k: Stat.over(getattr(o.metrics, k) for o in outs) for k in DATA_KEYS},
            "range_m": [min(s[0] for s in spans), max(s[1] for s in spans)] if spans
            else None}
