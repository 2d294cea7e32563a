"""The closed loop in MuJoCo: configuration, one run, Monte-Carlo summary and report."""

from ledsim.loop.closed_loop import ClosedLoop, run_once
from ledsim.loop.outcome import RunOutcome, Trace
from ledsim.loop.registry import PHYSICS_SCENARIOS
from ledsim.loop.report import RunSummary, run_many, write_run
from ledsim.loop.run_config import RunConfig

__all__ = ["ClosedLoop", "RunOutcome", "Trace", "run_once", "PHYSICS_SCENARIOS", "RunConfig",
           "RunSummary", "run_many", "write_run"]
