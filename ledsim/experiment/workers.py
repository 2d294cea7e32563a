"""The worker processes of :func:`ledsim.experiment.montecarlo.run_jobs`, which can be stopped at
any moment: plain processes with one pipe each, driven from the calling thread (no
manager thread or queue feeder that the interpreter's exit would wait for).

A worker ignores Ctrl-C (its parent handles it) and dies with its parent (Linux
``PR_SET_PDEATHSIG``); :meth:`Workers.stop` ends it with SIGTERM, then SIGKILL after
:data:`STOP_GRACE` s. Importing this module does not import numpy.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import pickle
import signal
import sys
import time
import traceback
from collections.abc import Callable
from multiprocessing.connection import wait

from ledsim.files.outputs import deferred_sigint

#: Seconds a worker gets to end after SIGTERM (or, its jobs done, after being told to
#: stop) before SIGKILL: part of the 2 s in which Ctrl-C ends a ``ledsim`` command.
STOP_GRACE = 0.5


class WorkerDied(RuntimeError):
    """A worker process ended while it ran a job (killed, out of memory, a crash)."""

    def __init__(self, proc, job: int):
        proc.join(STOP_GRACE)  # for its exit code
        super().__init__(f"worker process {proc.pid} died while running job {job} "
                         f"(exit code {proc.exitcode})")


class RemoteTraceback(Exception):
    """The traceback, in a worker, of an exception a job raised there (its cause)."""

    def __str__(self) -> str:
        return f"\n\"\"\"\n{self.args[0]}\"\"\""


class Workers:
    """``n`` processes, each running ``fn`` on the jobs sent to it, one at a time.

    Use as a context manager: on leaving, the workers are stopped, politely if the
    block ended normally, else at once (:meth:`stop`). ``report`` is called in a worker
    with the index of the job it starts (None when it ends), e.g. to route the job's
    progress reports.
    """

    def __init__(self, fn: Callable, n: int, report: Callable[[int | None], None]):
        ctx = multiprocessing.get_context()
        # A forkserver's workers are its children, not ours: their parent is not checked.
        parent = None if ctx.get_start_method() == "forkserver" else os.getpid()
        self.procs, self.links = [], []
        try:
            # A Ctrl-C between a fork and its bookkeeping would leave a worker nobody
            # stops (it would wait on its pipe forever, and the exit for it): held back
            # until all have started, then raised here, where they are stopped.
            with deferred_sigint():
                for _ in range(n):
                    here, there = ctx.Pipe()
                    self.links.append(here)
                    self.procs.append(ctx.Process(target=_serve, name="ledsim-worker",
                                                  args=(there, fn, report, parent)))
                    self.procs[-1].start()
                    there.close()
        except BaseException:
            with deferred_sigint():
                self.stop(polite=False)
            raise

    def __enter__(self) -> Workers:
        return self

    def __exit__(self, kind, exc, tb) -> None:
        with deferred_sigint():  # quick either way: a Ctrl-C waits for it
            self.stop(polite=kind is None)

    def send(self, i: int, k: int, job) -> None:
        """Job ``k`` to worker ``i`` (which must be idle)."""
        try:
            self.links[i].send((k, job))
        except OSError:
            raise WorkerDied(self.procs[i], k) from None

    def ready(self, busy: list[int], timeout: float) -> list[int]:
        """Those of the workers ``busy`` whose reply (or end) is there, waiting up to
        ``timeout`` s for one."""
        ready = wait([self.links[i] for i in busy], timeout=timeout)
        return [i for i in busy if self.links[i] in ready]

    def receive(self, i: int, k: int) -> tuple[bool, object]:
        """The reply of worker ``i`` to job ``k``: ``(True, result)`` or ``(False,
        exception)``, the exception caused by the worker's traceback."""
        try:
            k_, ok, value = self.links[i].recv()
        except (EOFError, OSError):
            return False, WorkerDied(self.procs[i], k)
        if ok:
            return True, value
        exc, tb = value
        exc.__cause__ = RemoteTraceback(tb)
        return False, exc

    def stop(self, polite: bool) -> None:
        """End the workers: ``polite`` (all jobs done) tells them to, else SIGTERM; any
        still alive after :data:`STOP_GRACE` s gets SIGKILL. Closes the pipes."""
        for p, link in zip(self.procs, self.links, strict=False):
            if polite:
                try:
                    link.send(None)
                except OSError:
                    pass
            elif p.pid is not None:
                p.terminate()
        deadline = time.monotonic() + STOP_GRACE
        for p in self.procs:
            if p.pid is not None:
                p.join(max(0.0, deadline - time.monotonic()))
        for p in self.procs:
            if p.pid is not None and p.exitcode is None:
                p.kill()
                p.join()
        for link in self.links:
            link.close()


def _die_with_parent(parent: int | None = None) -> None:
    """Ask the kernel to end this worker when its parent dies (Linux; no-op elsewhere),
    and leave Ctrl-C to the parent, which stops the workers itself."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL("libc.so.6", use_errno=True)
            libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
        except OSError:
            pass
    if parent is not None and os.getppid() != parent:  # it died before the prctl
        os._exit(1)


def _portable(exc: BaseException) -> tuple[BaseException, str]:
    """``exc`` and its traceback as text, in a form that survives the pipe (an exception
    that does not pickle becomes a RuntimeError of its text)."""
    tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:
        exc = RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc, tb


def _serve(link, fn, report, parent: int) -> None:
    """A worker: ``(k, job)`` from ``link``, ``(k, True, fn(job))`` or ``(k, False,
    (exception, traceback))`` back, until None or the parent's end closes."""
    _die_with_parent(parent)
    if "torch" in sys.modules:  # two workers on two cores, not four threads fighting
        sys.modules["torch"].set_num_threads(1)
    try:
        while (item := link.recv()) is not None:
            k, job = item
            report(k)
            try:
                reply = (k, True, fn(job))
            except BaseException as exc:
                reply = (k, False, _portable(exc))
            finally:
                report(None)
            try:
                link.send(reply)
            except (pickle.PicklingError, TypeError, AttributeError) as exc:  # no pickle
                link.send((k, False, _portable(exc)))
    except (EOFError, OSError):  # the parent is gone (its SIGTERM is on the way)
        pass
