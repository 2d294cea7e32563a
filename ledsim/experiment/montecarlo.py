"""The one Monte-Carlo runner: a list of independent jobs, serial, on worker processes
or on a Ray cluster (:func:`run_jobs_ray`).

Every table, ``ledsim evaluate``, ``ledsim run`` and the disturbance table go through
:func:`run_jobs`. A job is ``fn(arg)`` with a picklable ``arg``; each job derives all its
random numbers from its own seed, so results do not depend on the number of workers or on
the order in which they finish. Workers (:mod:`ledsim.experiment.workers`) run one torch thread each
and die with their parent (Linux ``PR_SET_PDEATHSIG``), so a killed ``ledsim run`` leaves
no orphans behind; Ctrl-C or a failed job stops them within
:data:`~ledsim.experiment.workers.STOP_GRACE` s.
"""

from __future__ import annotations

import multiprocessing
import os
import socket
import sys
from collections.abc import Callable, Sequence
from functools import partial
from typing import TypeVar

from tqdm.auto import tqdm

from ledsim.errors import LedsimError
from ledsim.experiment.workers import (  # noqa: F401 (aliases: the errors run_jobs raises)
    RemoteTraceback,
    WorkerDied,
    Workers,
)
from ledsim.files.outputs import check_interrupt

#: One BLAS/OpenMP thread per process, so that N workers use N cores. Effective only
#: when set before numpy loads (Ray: its runtime environment; the CLI, the scripts:
#: :func:`pin_blas_threads` first thing).
WORKER_ENV = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                               "MKL_NUM_THREADS")}


def pin_blas_threads() -> None:
    """Put :data:`WORKER_ENV` into ``os.environ``; a value the user set wins.
    Importing this module does not import numpy."""
    for var, value in WORKER_ENV.items():
        os.environ.setdefault(var, value)


T = TypeVar("T")
R = TypeVar("R")

#: Seconds between two looks at the workers' progress (the bar, a swallowed Ctrl-C).
TICK = 0.5


#: How a running job reports its progress (:func:`report_progress`), set by
#: :func:`run_jobs` around each job: in this process, or in a worker.
_REPORT: Callable[[float], None] | None = None


def report_progress(share: float) -> None:
    """Called by a job as it goes, with the share of it done so far (0-1): the bar of
    :func:`run_jobs` moves within the job by that share of its size (a batch of 16
    seeds moves it seed by seed, not in one jump). Outside a job, nothing happens."""
    if _REPORT is not None:
        _REPORT(share)


def _route_reports(shares, k: int | None) -> None:
    """In a worker: the reports of job ``k`` go to its share in ``shares`` (None: the
    job ended)."""
    global _REPORT
    _REPORT = None if k is None else partial(shares.__setitem__, k)


def run_jobs(fn: Callable[[T], R], jobs: Sequence[T], workers: int = 1, desc: str = "",
             progress: bool = True,
             on_result: Callable[[T, R], None] | None = None,
             sizes: Sequence[int] | None = None) -> list[R]:
    """``[fn(job) for job in jobs]``, on ``workers`` processes when that helps.

    Ctrl-C (KeyboardInterrupt) or a failed job stops the workers at once (SIGTERM, then
    SIGKILL after :data:`~ledsim.experiment.workers.STOP_GRACE` s); the exception is then raised
    here, a job's caused by its traceback in the worker.

    Args:
        fn: a module-level function (it is pickled to the workers).
        jobs: its arguments, one per job.
        workers: processes; 1 runs in this process.
        desc: label of the progress bar (on stderr).
        progress: show the progress bar.
        on_result: called in this process with ``(job, result)`` as each job finishes
            (in job order), e.g. to save it so that an interrupted run can resume.
        sizes: what each job counts for on the bar (a batch of seeds: its seeds);
            None: one each.
    """
    sizes = [1] * len(jobs) if sizes is None else list(sizes)
    bar = _bar_options(int(sum(sizes)), desc, progress)
    workers = min(workers, len(jobs))
    if workers <= 1:
        return _collect_here(fn, jobs, bar, on_result, sizes)
    shares = multiprocessing.Array("d", len(jobs), lock=False)
    # Ctrl-C or a failed job: leaving the block stops the workers at once.
    with Workers(fn, workers, partial(_route_reports, shares)) as pool:
        return _collect(jobs, pool, bar, on_result, sizes, shares)


def run_jobs_ray(fn: Callable[[T], R], jobs: Sequence[T], workers: int = 2,
                 address: str | None = None, desc: str = "", progress: bool = True,
                 on_result: Callable[[T, R], None] | None = None) -> list[R]:
    """:func:`run_jobs` on Ray: a running cluster at ``address`` (e.g. ``auto`` or
    ``ray://head:10001``), or a private local instance of ``workers`` CPUs when None.

    Each job takes one CPU and runs with one BLAS thread (:data:`WORKER_ENV`).
    ``on_result`` is called here, in this process, as jobs finish (in any order); the
    returned list is in job order.
    """
    try:
        import ray
    except ImportError:
        raise LedsimError("--backend ray needs Ray: pip install 'ledsim[ray]'") from None
    started = not ray.is_initialized()
    if started:
        _check_reachable(address)
        kw = dict(num_cpus=workers) if address is None else {}
        try:
            ray.init(address=address, include_dashboard=False, log_to_driver=False,
                     configure_logging=False, runtime_env={"env_vars": WORKER_ENV}, **kw)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            raise LedsimError(f"--address {address!r}: no Ray cluster to join ({first})") \
                from None
    pending: dict = {}
    results: dict[int, R] = {}
    try:
        remote = ray.remote(num_cpus=1, max_retries=2)(fn)
        pending = {remote.remote(job): k for k, job in enumerate(jobs)}
        with tqdm(**_bar_options(len(jobs), desc, progress)) as bar:
            while pending:
                ready, _ = ray.wait(list(pending), num_returns=1)
                k = pending.pop(ready[0])
                results[k] = ray.get(ready[0])
                if on_result is not None:
                    on_result(jobs[k], results[k])
                bar.update()
    except KeyboardInterrupt:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started:
            ray.shutdown()
    return [results[k] for k in range(len(jobs))]


def _check_reachable(address: str | None, timeout: float = 5.0) -> None:
    """Refuse at once a ``HOST:PORT`` (or ``ray://HOST:PORT``) that accepts no connection:
    Ray itself retries for minutes before it gives up."""
    if address is None or address == "auto":
        return
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        raise LedsimError(f"--address {address!r} is not allowed: use auto, HOST:PORT or "
                          "ray://HOST:PORT")
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as exc:
        raise LedsimError(f"--address {address!r}: cannot connect ({exc.strerror or exc})") \
            from None


def _bar_options(total: int, desc: str, progress: bool) -> dict:
    """tqdm options of every runner's progress bar (on stderr, gone when done)."""
    return dict(total=total, desc=desc, disable=not progress, leave=False, file=sys.stderr)


def _move(shown, position: float) -> None:
    """The bar forward to ``position`` (jobs' sizes, to two decimals: tqdm prints it,
    and a sum of updates would print its round-off)."""
    position = round(position, 2)
    if position > shown.n:
        shown.n = position
        shown.refresh()


def _report_here(shown, at: float, size: float, share: float) -> None:
    check_interrupt()  # a Ctrl-C that Python swallowed (in a callback) stops the job too
    _move(shown, at + size * share)


def _collect_here(fn, jobs, bar: dict, on_result, sizes: list) -> list:
    """``fn`` of each job in this process, in order; the bar follows each job's reports
    and advances by its size when it is done."""
    global _REPORT
    results, done = [], 0.0
    with tqdm(**bar) as shown:
        for job, size in zip(jobs, sizes, strict=True):
            _REPORT = partial(_report_here, shown, done, size)
            try:
                res = fn(job)
            finally:
                _REPORT = None
            if on_result is not None:
                on_result(job, res)
            results.append(res)
            done += size
            _move(shown, done)
    return results


def _collect(jobs, pool: Workers, bar: dict, on_result, sizes: list, shares) -> list:
    """The results of ``jobs`` on the workers of ``pool``, handed out one at a time to
    whichever is free, returned (and given to ``on_result``) in job order. The bar shows
    the finished jobs' sizes plus the running ones' shares of theirs, looked at every
    :data:`TICK` s. A failed job's exception is raised when its turn comes, so the jobs
    before it still reach ``on_result`` first."""
    todo = iter(range(len(jobs)))
    running: dict[int, int] = {}  # worker -> index of the job it runs
    done: dict[int, tuple[bool, object]] = {}
    failed = len(jobs)  # the first failed job: no job after it is handed out

    def hand_out(i: int) -> None:
        k = next(todo, None)
        if k is not None and k < failed:
            pool.send(i, k, jobs[k])
            running[i] = k

    results = []
    with tqdm(**bar) as shown:
        for i in range(len(pool.procs)):
            hand_out(i)
        while len(results) < len(jobs):
            check_interrupt()  # a Ctrl-C that Python swallowed
            for i in pool.ready(list(running), TICK):
                k = running.pop(i)
                done[k] = pool.receive(i, k)
                if not done[k][0]:
                    failed = min(failed, k)
                hand_out(i)
            while len(results) in done:
                ok, value = done.pop(len(results))
                if not ok:
                    raise value
                if on_result is not None:
                    on_result(jobs[len(results)], value)
                results.append(value)
            k = len(results)
            _move(shown, sum(sizes[:k]) + sum(size * shares[j] for j, size in
                                              enumerate(sizes[k:], k)))
    return results
