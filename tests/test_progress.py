"""run_jobs' bar moves within a job as the job reports its share done (a batch of seeds
moves it seed by seed), in this process and on workers."""

import time

import pytest

import ledsim.experiment.montecarlo as mc


class _Bar:
    positions: list = []

    def __init__(self, **kw):
        self.n = 0
        _Bar.positions = []

    def refresh(self):
        _Bar.positions.append((time.perf_counter(), self.n))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def _halfway(job):
    mc.report_progress(0.5)
    time.sleep(job)
    mc.report_progress(1.0)
    return job


@pytest.mark.parametrize("workers", [1, 2])
def test_the_bar_moves_within_a_job(monkeypatch, workers):
    monkeypatch.setattr(mc, "tqdm", _Bar)
    t0 = time.perf_counter()
    out = mc.run_jobs(_halfway, [2.5, 0.0], workers=workers, sizes=[4, 2])
    assert out == [2.5, 0.0]
    # The bar moved while the first job (2.5 s) still ran: by half of its 4 seeds (and,
    # on workers, the second job's 2, done beside it).
    early = [n for t, n in _Bar.positions if t - t0 < 2.0]
    assert early and 0 < max(early) < 6
    assert _Bar.positions[-1][1] == 6


def test_report_outside_a_job_does_nothing():
    mc.report_progress(0.3)  # no bar, no error


def test_the_closed_loop_reports_its_share(monkeypatch):
    from ledsim.loop.closed_loop import ClosedLoop
    from ledsim.loop.run_config import RunConfig

    seen = []
    monkeypatch.setattr(mc, "_REPORT", seen.append)
    ClosedLoop(RunConfig(scenario="align", estimator="oracle", seconds=1.0), [0, 1]).run()
    assert seen and seen[-1] == 1.0 and seen == sorted(seen)
