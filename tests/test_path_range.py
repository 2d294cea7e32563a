"""The saturation warning covers the run's whole path (issue 49): a range that the
transmitter's drift closes into the receiver's clipping is said before the run starts,
with where and when, and ``results.json`` says so."""

import json

import pytest
from conftest import run_cli

from ledsim.loop.path_range import range_path, saturation_onset
from ledsim.loop.run_config import RunSpec

CLOSING = dict(link="bluecomm-200", water="coastal", distance=30.0,
               disturbances=("transmitter:drift=-0.5,drift_until=50",))


def test_the_path_closes_with_the_drift_and_saturates_where_the_peak_fills_the_scale():
    spec = RunSpec(**CLOSING, seconds=60.0)
    t, d = range_path(spec)
    assert d[0] == 30.0 and d[-1] == pytest.approx(5.0) and t[-1] == pytest.approx(60.0)
    distance, when = saturation_onset(spec)
    assert 8.5 < distance < 9.5 and when == pytest.approx((30.0 - distance) / 0.5, abs=0.1)
    assert saturation_onset(RunSpec(**CLOSING, seconds=30.0)) is None  # still 15 m off
    start, at = saturation_onset(RunSpec(**{**CLOSING, "distance": 5.0}, seconds=1.0))
    assert (start, at) == (5.0, 0.0)


def test_a_run_that_closes_into_clipping_is_warned_and_says_so(tmp_path):
    r = run_cli("run", "--link", "bluecomm-200", "--water", "coastal", "--distance", "30",
                "--disturbance", "transmitter:drift=-0.5,drift_until=50", "--seconds",
                "60", "--seeds", "1", "--estimator", "oracle", "--no-plot", "--out",
                str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    notes = [line for line in r.stderr.splitlines() if "saturates" in line]
    assert len(notes) == 1 and "from 9.0 m on, 42.0 s into the run" in notes[0], r.stderr
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    assert res["receiver_saturates"] is True
