"""The command line's flags come from the run's spec: one flag per spec name, and a
command line that gives back any spec."""

import pytest

from ledsim.cli import build_parser
from ledsim.cli.spec_flags import flags, spec_argv, spec_values
from ledsim.loop.run_config import FLAT, RunSpec


def _run_args(argv):
    return build_parser().parse_args(["run", "--out", "x", *argv])


def test_every_spec_name_has_a_run_flag():
    assert set(flags()) == set(FLAT)
    assert set(spec_values(_run_args([]))) == set(FLAT)


def test_the_run_commands_defaults_are_the_specs_but_its_link():
    from ledsim.radiometry.link_presets import DEFAULT_LINK

    assert RunSpec(**spec_values(_run_args([]))) == RunSpec(link=DEFAULT_LINK)


@pytest.mark.parametrize("spec", [
    RunSpec(link="paper"),
    RunSpec(estimator="ekf", disturbances=("vibration:frequency=3", "occlusion"), link="luma",
            water="coastal", attenuation=0.4, depth=20.0, transmitter_depth=18.5,
            receiver_dome=True, imu=False, station_keeping=False, supervision=False,
            imu_noise=("dvl_noise=0.01", "fix_noise=0.5"), station_keeping_gains=("kp=2",),
            seconds=12.5, initial_angle=-0.2, acquisition="warm-up", seeds=3, workers=1,
            window=5.0, noise_scale=1.5, torque_limit=0.02, particles=500,
            filter_distance="configured", omega_model="none", integrator="euler",
            checkpoint="k.safetensors", scene="s.xml", bit_rate=2e6, distance=12.0),
])
def test_a_spec_goes_to_a_command_line_and_back(spec):
    argv = spec_argv(spec)
    assert RunSpec(**spec_values(_run_args(argv))) == spec
    assert spec_argv(spec.flat()) == argv  # from results.json's "spec" alike


def test_a_sweeps_rows_give_every_spec_name():
    from ledsim.loop.sweep import COLUMNS, DATA_COLUMNS, LATER_SPEC, SPEC_COLUMNS

    grid = {"disturbances": "disturbance", "seeds": "seed", "workers": None}
    assert {grid.get(n, n) for n in FLAT} - {None} <= set(COLUMNS)
    # appended: old columns keep places (the data delivered after the spec, then the
    # spec's names added since)
    tail = SPEC_COLUMNS + DATA_COLUMNS + LATER_SPEC
    assert COLUMNS[-len(tail):] == tail
    assert DATA_COLUMNS[:5] == ("goodput_bits", "ideal_bits", "outages", "outage_s",
                                "range_m")


def test_a_cell_of_an_older_sweep_leaves_the_new_columns_blank():
    from ledsim.loop.sweep import COLUMNS, DATA_COLUMNS, LATER_SPEC, SPEC_COLUMNS, _csv

    new = SPEC_COLUMNS + DATA_COLUMNS + LATER_SPEC
    row = {k: 1.0 for k in COLUMNS if k not in new}
    text = _csv([row], COLUMNS)
    assert text.splitlines()[1].endswith("," * len(new))
