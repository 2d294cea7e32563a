"""The one Monte-Carlo runner: a list of independent jobs, serial or on worker processes.

Every table, ``ledsim evaluate``, ``ledsim run`` and the disturbance table go through
:func:`run_jobs`. A job is ``fn(arg)`` with a picklable ``arg``; each job derives all its
random numbers from its own seed, so results do not depend on the number of workers or on
the order in which they finish. Workers run one torch thread each and die with their
parent (Linux ``PR_SET_PDEATHSIG``), so a killed ``ledsim run`` leaves no orphans behind.
"""

from __future__ import annotations

import ctypes
import signal
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import TypeVar

from tqdm.auto import tqdm

T = TypeVar("T")
R = TypeVar("R")


def _die_with_parent() -> None:
    """Ask the kernel to end this worker when its parent dies (Linux; no-op elsewhere)."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL("libc.so.6", use_errno=True)
            libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
        except OSError:
            pass
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C


def _init_worker() -> None:
    _die_with_parent()
    if "torch" in sys.modules:  # two workers on two cores, not four threads fighting
        sys.modules["torch"].set_num_threads(1)


def run_jobs(fn: Callable[[T], R], jobs: Sequence[T], workers: int = 1, desc: str = "",
             progress: bool = True) -> list[R]:
    """``[fn(job) for job in jobs]``, on ``workers`` processes when that helps.

    Args:
        fn: a module-level function (it is pickled to the workers).
        jobs: its arguments, one per job.
        workers: processes; 1 runs in this process.
        desc: label of the progress bar (on stderr).
        progress: show the progress bar.
    """
    bar = dict(total=len(jobs), desc=desc, disable=not progress, leave=False,
               file=sys.stderr)
    workers = min(workers, len(jobs))
    if workers <= 1:
        return [fn(j) for j in tqdm(jobs, **bar)]
    with ProcessPoolExecutor(workers, initializer=_init_worker) as pool:
        return list(tqdm(pool.map(fn, jobs, chunksize=1), **bar))
