"""Older home of the loop of many seeds: :class:`~ledsim.loop.closed_loop.ClosedLoop`
steps any number of seeds together, and :func:`run_batch` is kept here under its
older path."""

from ledsim.loop.closed_loop import ClosedLoop, run_batch

#: Older name of :class:`~ledsim.loop.closed_loop.ClosedLoop`.
BatchedClosedLoop = ClosedLoop

__all__ = ["BatchedClosedLoop", "run_batch"]
