"""The saturation check covers the run's whole path (issue 49): a range that the
transmitter's drift closes into the receiver's clipping is refused before the run
starts, with where and when; the detectors' gain control keeps every preset's bare
detector in range down to 1 m."""

import pytest
from conftest import run_cli

from ledsim.loop.path_range import range_path, saturation_onset
from ledsim.loop.run_config import RunSpec

# behind a 10 deg lens bluecomm-200's PMT fills its scale under 1.46 m in coastal water
CLOSING = dict(link="bluecomm-200", water="coastal", distance=30.0, lens_field_deg=10.0,
               disturbances=("transmitter:drift=-0.5,drift_until=58",))


def test_the_path_closes_with_the_drift_and_saturates_where_the_peak_fills_the_scale():
    spec = RunSpec(**CLOSING, seconds=60.0)
    t, d = range_path(spec)
    assert d[0] == 30.0 and d[-1] == pytest.approx(1.0) and t[-1] == pytest.approx(60.0)
    distance, when = saturation_onset(spec)
    assert 1.4 < distance < 1.5 and when == pytest.approx((30.0 - distance) / 0.5, abs=0.1)
    assert saturation_onset(RunSpec(**CLOSING, seconds=50.0)) is None  # still 5 m off
    start, at = saturation_onset(RunSpec(**{**CLOSING, "distance": 1.2}, seconds=1.0))
    assert (start, at) == (1.2, 0.0)


@pytest.mark.parametrize("link", ["aquaoptical", "luma", "bluecomm-200"])
@pytest.mark.parametrize("water", ["pure-sea", "clear-ocean", "coastal", "harbour"])
def test_no_preset_clips_down_to_a_metre(link, water):
    """The detector's gain control (a PMT's control voltage, an APD's bias) holds every
    preset's bare detector's peak power in range from its FEC range to 1 m."""
    spec = RunSpec(link=link, water=water, distance=1.0, seconds=1.0)
    assert saturation_onset(spec) is None


def test_a_run_that_closes_into_clipping_is_refused_before_it_starts(tmp_path):
    r = run_cli("run", "--link", "bluecomm-200", "--water", "coastal", "--distance", "30",
                "--lens-field-deg", "10", "--disturbance",
                "transmitter:drift=-0.5,drift_until=58", "--seconds", "60", "--seeds", "1",
                "--estimator", "oracle", "--no-plot", "--out", str(tmp_path / "o"))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "from 1.46 m on, 57.1 s into the run (along its path)" in r.stderr
    assert not (tmp_path / "o").exists()
