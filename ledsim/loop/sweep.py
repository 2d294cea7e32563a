"""Parameter sweeps of the closed loop: a grid of runs, on this machine or a Ray cluster.

A sweep is the product estimators x disturbances x distances x noise scales x seeds;
each cell is one :func:`~ledsim.loop.closed_loop.run_once`. Cells derive every random
number from their own seed, so a cell's result does not depend on where or in which
order it runs: the ``local`` and ``ray`` backends give the same ``results.csv`` except
for the timing columns (:data:`TIMING_COLUMNS`).

The output folder holds ``cells/`` (one JSON file per finished cell, written
atomically as it finishes), and, once every cell is done, ``results.csv`` (one row per
run, grid order), ``summary.csv`` (mean and spread over seeds) and ``summary.png``.
Running the same command again skips the cells already in ``cells/``: an interrupted
sweep resumes where it stopped.
"""

from __future__ import annotations

import csv
import hashlib
import io
import itertools
import json
import logging
import re
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from ledsim.errors import LedsimError
from ledsim.files.outputs import atomic_write_text
from ledsim.files.results import to_jsonable
from ledsim.loop.report import Stat
from ledsim.loop.run_config import FLAT, RunConfig
from ledsim.physics.scene import DEFAULT_DEPTH

log = logging.getLogger("ledsim")

BACKENDS = ("local", "ray")
#: "none" stands for no disturbance; "+" joins several disturbances into one cell.
NO_DISTURBANCE = "none"
#: Columns of ``results.csv`` that describe the cell.
CELL_COLUMNS = ("scenario", "estimator", "disturbance", "distance", "noise_scale", "seed",
                "seconds", "supervision", "imu", "station_keeping", "link", "water",
                "bit_rate", "depth")
#: Columns that measure the run (units as in :class:`~ledsim.loop.run_metrics.RunMetrics`).
METRIC_COLUMNS = ("rmse_x1", "rmse_x2", "rmse_steady_x1", "rmse_steady_x2",
                  "alignment_time", "availability", "mean_power", "recovery_time",
                  "lost_share", "detection_delay", "losses", "snr_db", "ber",
                  "throughput_bps", "fec_share", "geometry_share", "hull_error_rms",
                  "navigation_error_rms", "received_power_w", "loss_events",
                  "false_loss_events", "reseeds", "silent_error_share")
#: Columns that depend on the machine and its load (the only ones reruns may change).
TIMING_COLUMNS = ("us_per_step", "realtime_factor")
#: The rest of the run's spec, by its names (:data:`~ledsim.loop.run_config.FLAT`): every
#: setting a cell ran with that the columns above do not give (a repeatable one's items
#: joined by ``;``); then what the run delivered (``range_m``: nearest;farthest); then
#: the spec's names added since (LATER_SPEC). New columns go last: none moves.
LATER_SPEC = ("node_error",)
SPEC_COLUMNS = tuple(n for n in FLAT if n not in CELL_COLUMNS + LATER_SPEC and n not in (
    "estimator", "disturbances", "distance", "noise_scale", "seeds", "workers"))
DATA_COLUMNS = ("goodput_bits", "ideal_bits", "outages", "outage_s", "range_m", "edge_goodput_bits", "edge_ideal_bits")  # noqa: E501
COLUMNS = CELL_COLUMNS + METRIC_COLUMNS + TIMING_COLUMNS + SPEC_COLUMNS + DATA_COLUMNS + LATER_SPEC


def split_disturbance(cell: str) -> tuple[str, ...]:
    """The disturbance specs of one sweep cell: ``none`` -> (), ``a+b`` -> (a, b)."""
    if cell.strip() == NO_DISTURBANCE:
        return ()
    return tuple(p for p in re.split(r"\+(?=[a-z])", cell) if p)


#: The link's settings at their defaults stay out of a cell's key, so that a sweep
#: folder of the paper's bench from before them resumes.
_LINK_DEFAULTS = {"link": "paper", "water": None, "attenuation": None, "bit_rate": None,
                  "depth": DEFAULT_DEPTH, "transmitter_depth": None,
                  "receiver_dome": False, "sea_depth": None, "gimbal": None,
                  "receiver": None, "initial_elevation": 0.0, "channel_mismatch": 0.0,
                  "transmitter_aimed": False, "lens_field_deg": None}


@dataclass(frozen=True)
class Cell:
    """One run of the grid (plain data: it travels to processes and Ray workers)."""

    estimator: str
    disturbance: str
    distance: float
    noise_scale: float
    seed: int

    def key(self, base: RunConfig) -> str:
        """Identifies the cell and every setting that changes its result."""
        common = {k: v for k, v in base.flat().items()
                  if k not in ("seeds", "workers", "estimator", "disturbances", "distance",
                               "noise_scale")
                  and not (k in _LINK_DEFAULTS and v == _LINK_DEFAULTS[k])}
        return json.dumps({**asdict(self), **common}, sort_keys=True)

    def file_name(self, base: RunConfig) -> str:
        return hashlib.sha1(self.key(base).encode()).hexdigest()[:20] + ".json"


@dataclass
class SweepGrid:
    """The grid of a sweep and the settings every cell shares.

    Attributes:
        estimators: keys of :data:`~ledsim.loop.run_config.LOOP_ESTIMATORS`.
        disturbances: cells of disturbance specs (:func:`split_disturbance`).
        distances: link distances d [m].
        noise_scales: multipliers of the measurement-noise std [-].
        seeds: runs per combination (seeds 0..seeds-1).
        base: everything else (scenario, seconds, particles, torque limit, ...).
    """

    estimators: Sequence[str]
    disturbances: Sequence[str]
    distances: Sequence[float]
    noise_scales: Sequence[float]
    seeds: int
    base: RunConfig

    def cells(self) -> list[Cell]:
        return [Cell(e, d, float(r), float(n), s) for e, d, r, n, s in itertools.product(
            self.estimators, self.disturbances, self.distances, self.noise_scales,
            range(self.seeds))]

    def config(self, cell: Cell) -> RunConfig:
        return replace(self.base, estimator=cell.estimator,
                       disturbances=split_disturbance(cell.disturbance),
                       distance=cell.distance, noise_scale=cell.noise_scale, seeds=1,
                       workers=1)

    def validate(self) -> None:
        """Every combination is a valid run; refused in one line before any work."""
        for name, seq in (("--estimator", self.estimators), ("--disturbance",
                          self.disturbances), ("--distance", self.distances),
                          ("--noise-scale", self.noise_scales)):
            if not seq:
                raise LedsimError(f"{name}: give at least one value")
        from ledsim.loop.build.estimation import check_checkpoint

        for cell in {Cell(e, d, r, n, 0) for e, d, r, n in itertools.product(
                self.estimators, self.disturbances, self.distances, self.noise_scales)}:
            cfg = self.config(cell)
            cfg.validate()
            check_checkpoint(cfg)


def run_cell(job: tuple[RunConfig, Cell]) -> dict:
    """One row of ``results.csv`` (module level: it is shipped to the workers)."""
    from ledsim import __version__
    from ledsim.loop.closed_loop import run_once

    cfg, cell = job
    out = run_once(cfg, cell.seed)
    m = out.metrics
    row = {"scenario": cfg.scenario, "estimator": cell.estimator,
           "disturbance": cell.disturbance, "distance": cell.distance,
           "noise_scale": cell.noise_scale, "seed": cell.seed, "seconds": cfg.run_seconds,
           "supervision": cfg.supervision, "imu": cfg.imu,
           "station_keeping": cfg.station_keeps and out.station_keeping is not False,
           "rmse_x1": m.rmse["x1"], "rmse_x2": m.rmse["x2"],
           "rmse_steady_x1": m.rmse_steady["x1"], "rmse_steady_x2": m.rmse_steady["x2"],
           "alignment_time": m.alignment_time, "availability": m.availability,
           "mean_power": m.mean_power, "recovery_time": m.recovery_time,
           "lost_share": m.lost_share, "detection_delay": m.detection_delay,
           "snr_db": m.snr_db, "ber": m.ber, "throughput_bps": m.throughput_bps,
           "fec_share": m.fec_share, "geometry_share": m.geometry_share,
           "losses": len(m.link_events), "hull_error_rms": m.hull_error_rms,
           "navigation_error_rms": m.navigation_error_rms,
           "us_per_step": out.us_per_step, "realtime_factor": out.realtime_factor,
           "link": cfg.link, "water": cfg.water, "bit_rate": cfg.data_bit_rate,
           "depth": cfg.depth,
           "received_power_w": m.mean_power, "loss_events": m.loss_events,
           "false_loss_events": m.false_loss_events, "reseeds": m.reseeds,
           "silent_error_share": m.silent_error_share, **{k: getattr(m, k) for k in
           DATA_COLUMNS}, "range_m": ";".join(f"{v:g}" for v in m.range_m or ())}
    flat = cfg.flat()
    row.update({n: ";".join(flat[n]) if isinstance(flat[n], tuple) else flat[n]
                for n in SPEC_COLUMNS + LATER_SPEC})
    return {"version": __version__, "row": to_jsonable(row)}


class SweepStore:
    """The folder of a sweep: finished cells in ``cells/``, tables and plot at the end."""

    def __init__(self, out: Path, grid: SweepGrid):
        self.out, self.grid = Path(out), grid
        self.cells_dir = self.out / "cells"

    def _path(self, cell: Cell) -> Path:
        return self.cells_dir / cell.file_name(self.grid.base)

    def load(self, cell: Cell) -> dict | None:
        """The saved row of ``cell``, or None when it has not finished (or the file is
        from another grid: the key is compared, not only the name)."""
        path = self._path(cell)
        if not path.is_file():
            return None
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError):
            return None
        return data["row"] if data.get("key") == cell.key(self.grid.base) else None

    def save(self, cell: Cell, result: dict) -> None:
        from ledsim import __version__

        if result["version"] != __version__:
            raise LedsimError(f"a worker runs ledsim {result['version']}, this machine "
                              f"{__version__}: install the same version on every node")
        self.cells_dir.mkdir(parents=True, exist_ok=True)
        atomic_write_text(self._path(cell), json.dumps(
            {"key": cell.key(self.grid.base), "row": result["row"]}, allow_nan=False))

    def write_tables(self, rows: list[dict], plot: bool = True) -> list[Path]:
        paths = [self.out / "results.csv", self.out / "summary.csv"]
        atomic_write_text(paths[0], _csv(rows, COLUMNS))
        summary = summarize_rows(rows)
        atomic_write_text(paths[1], _csv(summary, tuple(summary[0])))
        if plot:
            from ledsim.experiment.plotting import plot_sweep

            paths.append(plot_sweep(summary, self.out / "summary.png"))
        return paths


def _csv(rows: list[dict], columns: Sequence[str]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, columns, lineterminator="\n")
    w.writeheader()
    for r in rows:  # a cell finished by an older ledsim lacks the newer columns: blank
        w.writerow({k: ("" if r.get(k) is None else repr(r[k]) if isinstance(r[k], float)
                        else r[k]) for k in columns})
    return buf.getvalue()


def summarize_rows(rows: list[dict]) -> list[dict]:
    """Mean and spread (sample std) over seeds of each metric, per combination."""
    groups: dict[tuple, list[dict]] = {}
    keys = ("scenario", "estimator", "disturbance", "distance", "noise_scale")
    for r in rows:
        groups.setdefault(tuple(r[k] for k in keys), []).append(r)
    out = []
    for combo, rs in groups.items():
        s = dict(zip(keys, combo, strict=True), runs=len(rs))
        for m in ("rmse_steady_x1", "rmse_steady_x2", "availability", "recovery_time",
                  "lost_share", "fec_share", "throughput_bps"):
            stat = Stat.over(r[m] for r in rs)
            s[f"{m}_mean"], s[f"{m}_std"] = stat.mean, stat.std
            if m == "recovery_time":  # how many of the runs recovered
                s["recovery_time_n"] = stat.n
        out.append(s)
    return out


def run_sweep(grid: SweepGrid, out: str | Path, backend: str = "local",
              workers: int = 2, address: str | None = None, progress: bool = True,
              plot: bool = True) -> tuple[list[dict], list[Path]]:
    """Run every cell of ``grid`` not already finished in ``out``; write the tables.

    Args:
        grid: the sweep.
        out: output folder (created; reused to resume).
        backend: ``local`` (processes on this machine) or ``ray``.
        workers: processes (local) or CPUs of the local Ray instance (ray without
            ``address``).
        address: a running Ray cluster (``ray`` backend), e.g. ``auto`` or
            ``ray://head:10001``; None starts a local instance.
        progress: progress bar on stderr.
        plot: write ``summary.png``.

    Returns:
        the rows of ``results.csv`` and the paths written.
    """
    if backend not in BACKENDS:
        raise LedsimError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    grid.validate()
    store = SweepStore(Path(out), grid)
    cells = grid.cells()
    done = {c: r for c in cells if (r := store.load(c)) is not None}
    todo = [c for c in cells if c not in done]
    if done:
        log.info(f"resuming: {len(done)} of {len(cells)} runs already in {store.cells_dir}")
    jobs = [(grid.config(c), c) for c in todo]

    def keep(job, result) -> None:
        store.save(job[1], result)
        done[job[1]] = result["row"]

    from ledsim.experiment.montecarlo import run_jobs, run_jobs_ray

    if backend == "local":
        run_jobs(run_cell, jobs, workers, "sweep", progress, on_result=keep)
    else:
        run_jobs_ray(run_cell, jobs, workers, address, "sweep (ray)", progress,
                     on_result=keep)
    rows = [done[c] for c in cells]
    return rows, store.write_tables(rows, plot)
