"""Monte-Carlo over seeds of the closed loop, its summary and files (its printed table:
:mod:`ledsim.loop.table`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ledsim.experiment.montecarlo import run_jobs
from ledsim.files.outputs import atomic_write_bytes
from ledsim.files.results import DictAccess, write_json
from ledsim.loop.build.estimation import check_checkpoint, saturates, served
from ledsim.loop.closed_loop import run_batch
from ledsim.loop.outcome import RunOutcome, Trace
from ledsim.loop.over_seeds import (  # noqa: F401 (Stat and WINDOW_KEYS were here)
    WINDOW_KEYS,
    Stat,
    data_delivered,
    per_axis,
    summarize_windows,
)
from ledsim.loop.pcrb_runs import bound_summary
from ledsim.loop.run_config import RunConfig

#: Revision of ``results.json``'s layout: 2 added the physical link's keys (``link``,
#: ``water``, ``attenuation``, ``received_power_w``) and this one; 3 the losses
#: (``loss_events``, ``false_loss_events``, ``reseeds``, and the windows' estimate).
SCHEMA_VERSION = 3


@dataclass
class RunSummary(DictAccess):
    """What ``ledsim run`` writes to ``results.json`` (units as in :class:`RunMetrics`).

    ``link_events`` lists, per seed, each loss of the link as ``[t_lost, t_recovered]``
    [s]; ``recovery_time.n`` counts the seeds whose link came back after the event (of
    ``seeds``); ``imu`` says whether the control step used the vehicle's IMU, DVL and
    encoder, ``station_keeping`` whether the vehicle held its pose; ``hull_error_rms``
    and ``navigation_error_rms`` [m] are the hull's horizontal distance from its station
    and the navigation's horizontal error (None without a vehicle); ``windows`` (with
    ``--window``) the metrics of each window over the seeds; ``pointing_loss_db`` the
    mean pointing loss [dB] and ``outside_domain_share`` the share of the run the
    estimator was outside its training box (:class:`~ledsim.loop.run_metrics.RunMetrics`);
    ``pcrb_steady_x1`` [rad] and ``pcrb_steady_x2`` [rad/s] the root of the posterior
    Cramér-Rao bound over the steady window, along the seeds' true trajectories, and
    ``rmse_over_pcrb_x1``/``_x2`` the steady RMSE over it, with one Monte-Carlo standard
    error in ``rmse_over_pcrb_err_x1``/``_x2`` (:mod:`ledsim.loop.pcrb_runs`; none for the
    oracle, which reads the true state). ``link`` names the link preset (``paper``: the
    paper's bench), ``water`` its water (None: the bench's own), ``attenuation`` the
    power law's b [1/m] (a physical link's effective attenuation), ``received_power_w``
    photodiode 1's mean noise-free power [W] (``mean_power`` under its old name) and
    ``bit_rate`` the data's [bit/s] that ``snr_db``, ``ber``, ``throughput_bps`` and
    ``fec_share`` are at; ``receiver_saturates`` says whether the receiver's peak power
    at the distance reaches its digitiser's full scale (its samples clip: the estimates
    are biased); ``schema_version`` counts this layout's revisions; ``loss_events``,
    ``false_loss_events`` and ``reseeds`` count the losses the supervisor declared
    after the first acquisition, those that the data did not call for (the geometry
    allowed the link, no occluder shaded it, and the estimator's own phi was within 0.1
    rad of the truth), and the estimator's restarts, per seed
    (:class:`~ledsim.loop.run_metrics.RunMetrics`); ``spec`` the whole run by its flat
    names (:meth:`~ledsim.loop.run_config.RunSpec.flat`), which
    :meth:`~ledsim.loop.run_config.RunSpec.from_dict` reads back to rerun it; ``gimbal``
    and ``receiver`` the head run (``yaw`` with the ``pair``, or ``pan-tilt`` with the
    ``quad``), and on a pan-tilt head ``rmse_azimuth``, ``rmse_elevation`` and
    ``rmse_pointing`` [rad] (the RMS angle between the estimated and the true direction)
    with their ``rmse_steady_`` forms, beside ``rmse_x1``, the azimuth's, and the
    four-state bound's ``pcrb_steady_azimuth``, ``_elevation``, ``_pointing`` [rad] with
    the steady RMSE over each (``rmse_over_pcrb_azimuth``, ...) (None on one axis);
    ``goodput_bits`` the data bits delivered through the link's FEC code while the link
    was held, ``ideal_bits`` what the same path pointed perfectly delivers, ``outages``
    and ``outage_s`` [s] the stretches delivering under half the code's rate, and
    ``range_m`` the range's [nearest, farthest] [m], and ``edge_goodput_bits`` and
    ``edge_ideal_bits`` the two bit counts near the edge of the range the ideal
    delivers at (:mod:`ledsim.radiometry.goodput`)."""

    scenario: str
    estimator: str
    disturbances: list
    distance: float
    noise_scale: float
    seeds: int
    omega_model: str
    seconds: float
    rmse_x1: Stat
    rmse_x2: Stat
    rmse_steady_x1: Stat
    rmse_steady_x2: Stat
    alignment_time: Stat
    aligned_runs: int
    availability: Stat
    geometry_share: Stat
    mean_power: Stat
    recovery_time: Stat
    lost_share: Stat
    silent_error_share: Stat
    detection_delay: Stat
    held_delay: Stat
    snr_db: Stat
    ber: Stat
    throughput_bps: Stat
    fec_share: Stat
    bit_rate: float
    distance_served: bool
    filter_distance: str
    link_events: list
    supervision: bool
    imu: bool
    station_keeping: bool
    us_per_step: Stat
    realtime_factor: Stat
    hull_error_rms: Stat | None = None
    navigation_error_rms: Stat | None = None
    windows: list | None = None
    pointing_loss_db: Stat | None = None
    outside_domain_share: Stat | None = None
    pcrb_steady_x1: float | None = None
    pcrb_steady_x2: float | None = None
    receiver_saturates: bool = False
    rmse_over_pcrb_x1: float | None = None
    rmse_over_pcrb_x2: float | None = None
    rmse_over_pcrb_err_x1: float | None = None
    rmse_over_pcrb_err_x2: float | None = None
    link: str = "paper"
    water: str | None = None
    attenuation: float | None = None
    received_power_w: Stat | None = None
    schema_version: int = SCHEMA_VERSION
    depth: float | None = None
    transmitter_depth: float | None = None
    receiver_dome: bool | None = None
    loss_events: Stat | None = None
    false_loss_events: Stat | None = None
    reseeds: Stat | None = None
    spec: dict | None = None
    sea_depth: float | None = None
    gimbal: str | None = None
    receiver: str | None = None
    rmse_azimuth: Stat | None = None
    rmse_elevation: Stat | None = None
    rmse_pointing: Stat | None = None
    rmse_steady_azimuth: Stat | None = None
    rmse_steady_elevation: Stat | None = None
    rmse_steady_pointing: Stat | None = None
    pcrb_steady_azimuth: float | None = None
    pcrb_steady_elevation: float | None = None
    pcrb_steady_pointing: float | None = None
    rmse_over_pcrb_azimuth: float | None = None
    rmse_over_pcrb_elevation: float | None = None
    rmse_over_pcrb_pointing: float | None = None
    goodput_bits: Stat | None = None
    ideal_bits: Stat | None = None
    outages: Stat | None = None
    outage_s: Stat | None = None
    range_m: list | None = None
    edge_goodput_bits: Stat | None = None
    edge_ideal_bits: Stat | None = None


def summarize(cfg: RunConfig, outs: list[RunOutcome]) -> RunSummary:
    constants = cfg.world_config().constants

    def stat(get: Callable[[RunOutcome], float | None]) -> Stat:
        return Stat.over(get(o) for o in outs)

    return RunSummary(
        cfg.scenario, cfg.estimator, list(cfg.disturbances), cfg.distance, cfg.noise_scale,
        cfg.seeds, cfg.omega_model, cfg.run_seconds,
        rmse_x1=stat(lambda o: o.metrics.rmse["x1"]),
        rmse_x2=stat(lambda o: o.metrics.rmse["x2"]),
        rmse_steady_x1=stat(lambda o: o.metrics.rmse_steady["x1"]),
        rmse_steady_x2=stat(lambda o: o.metrics.rmse_steady["x2"]),
        alignment_time=stat(lambda o: o.metrics.alignment_time),
        aligned_runs=sum(o.metrics.alignment_time is not None for o in outs),
        availability=stat(lambda o: o.metrics.availability),
        geometry_share=stat(lambda o: o.metrics.geometry_share),
        mean_power=stat(lambda o: o.metrics.mean_power),
        recovery_time=stat(lambda o: o.metrics.recovery_time),
        lost_share=stat(lambda o: o.metrics.lost_share),
        silent_error_share=stat(lambda o: o.metrics.silent_error_share),
        detection_delay=stat(lambda o: o.metrics.detection_delay),
        held_delay=stat(lambda o: o.metrics.held_delay),
        snr_db=stat(lambda o: o.metrics.snr_db),
        ber=stat(lambda o: o.metrics.ber),
        throughput_bps=stat(lambda o: o.metrics.throughput_bps),
        fec_share=stat(lambda o: o.metrics.fec_share),
        bit_rate=cfg.data_bit_rate,
        distance_served=served(cfg), receiver_saturates=saturates(cfg),
        filter_distance=cfg.filter_distance,
        link_events=[{"seed": k, "lost_recovered": o.metrics.link_events}
                     for k, o in enumerate(outs)],
        supervision=cfg.supervision,
        imu=cfg.imu,
        station_keeping=cfg.station_keeps and all(o.station_keeping is not False
                                                  for o in outs),
        us_per_step=stat(lambda o: o.us_per_step),
        realtime_factor=stat(lambda o: o.realtime_factor),
        hull_error_rms=stat(lambda o: o.metrics.hull_error_rms),
        navigation_error_rms=stat(lambda o: o.metrics.navigation_error_rms),
        windows=summarize_windows(outs),
        pointing_loss_db=stat(lambda o: o.metrics.pointing_loss_db),
        outside_domain_share=stat(lambda o: o.metrics.outside_domain_share),
        **bound_summary(outs, int(round(cfg.steady_from / constants.Te)),
                        estimates=cfg.estimator != "oracle"),
        link=cfg.link,
        water=cfg.water if constants.link is None else constants.link.water.name,
        attenuation=constants.attenuation,
        received_power_w=stat(lambda o: o.metrics.mean_power),
        depth=cfg.depth, transmitter_depth=cfg.transmitter_depth,
        receiver_dome=cfg.receiver_dome,
        loss_events=stat(lambda o: o.metrics.loss_events),
        false_loss_events=stat(lambda o: o.metrics.false_loss_events),
        reseeds=stat(lambda o: o.metrics.reseeds), spec=cfg.flat(), sea_depth=cfg.sea_depth,
        gimbal=cfg.world.head[0], receiver=cfg.world.head[1], **per_axis(outs),
        **data_delivered(outs))


#: The most seeds one job steps together (a batch): larger batches gain little more
#: (64 seeds of 5 s in one batch took the wall time of four of 16).
MAX_BATCH = 16


def _job(args) -> list[RunOutcome]:
    cfg, seeds, keep = args
    return run_batch(cfg, seeds, keep_trace=keep, window=cfg.window)


def seed_batches(seeds: int, workers: int) -> list[list[int]]:
    """Seeds 0..seeds-1 in consecutive batches, at least one per worker and none over
    :data:`MAX_BATCH` seeds."""
    n = max(min(workers, seeds), -(-seeds // MAX_BATCH), 1)
    bounds = np.linspace(0, seeds, n + 1).round().astype(int)
    return [list(range(a, b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a]


def run_seeds(cfg: RunConfig, progress: bool = True, all_traces: bool = False
              ) -> tuple[RunSummary, list[RunOutcome]]:
    """Monte-Carlo over seeds 0..cfg.seeds-1: (summary, one :class:`RunOutcome` per
    seed, with its trace for seed 0, or for every seed with ``all_traces``).

    The seeds are stepped together in batches (:func:`seed_batches`), one job of the
    Monte-Carlo runner each (the progress bar counts seeds as a batch steps), through
    the one closed loop (:class:`~ledsim.loop.closed_loop.ClosedLoop`): a seed's numbers
    do not depend on its batch or on the number of workers."""
    cfg.validate()
    check_checkpoint(cfg)
    batches = seed_batches(cfg.seeds, cfg.workers)
    jobs = [(cfg, b, [all_traces or s == 0 for s in b]) for b in batches]
    outs = [o for batch in run_jobs(_job, jobs, cfg.workers,
                                    f"{cfg.scenario}/{cfg.estimator}", progress,
                                    sizes=[len(b) for b in batches])
            for o in batch]
    return summarize(cfg, outs), outs


def run_many(cfg: RunConfig, progress: bool = True) -> tuple[RunSummary, Trace]:
    """Monte-Carlo over seeds 0..cfg.seeds-1; returns (summary, trace of seed 0)
    (see :func:`run_seeds`)."""
    summary, outs = run_seeds(cfg, progress)
    return summary, outs[0].trace


def write_traces(outs: list[RunOutcome], out: Path) -> list[Path]:
    """``trace_seed<K>.npz`` for each seed K with a trace, in the folder ``out``: 1-D
    arrays in SI units, one row per control step (:meth:`Trace.series`)."""
    paths = []
    for k, o in enumerate(outs):
        if o.trace is not None:
            path = out / f"trace_seed{k}.npz"
            atomic_write_bytes(path, lambda tmp, o=o: np.savez_compressed(
                open(tmp, "wb"), **o.trace.series()))
            paths.append(path)
    return paths


def write_run(summary: RunSummary, trace: Trace | None, out: Path,
              plot: bool = True) -> list[Path]:
    """``results.json`` and (with ``plot``) ``run.png`` in the folder ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    paths = [write_json(out / "results.json", summary)]
    if trace is not None and plot:
        from ledsim.experiment.plotting import plot_run

        dist = ", ".join(summary.disturbances) or "no disturbance"
        paths.append(plot_run(trace, f"{summary.scenario} with {summary.estimator} — {dist}",
                              summary.estimator, out / "run.png"))
    return paths
