"""Hostile numbers and specs are refused at the edge: one line, exit 2, nothing written."""

import pytest
from conftest import assert_user_error, run_cli

from ledsim.physics.disturbances import DisturbanceError, parse_disturbance


@pytest.mark.parametrize("args,needle", [
    (["simulate", "--seconds", "inf"], "--seconds"),
    (["simulate", "--torque-frequency", "inf"], "--torque-frequency"),
    (["simulate", "--gimbal-angle", "nan"], "--gimbal-angle"),
    (["simulate", "--led-yaw", "nan"], "--led-yaw"),
    (["simulate", "--distance", "1e308"], "--distance"),
    (["simulate", "--distance", "1e-183"], "--distance"),  # its rays divided by zero
    (["run", "--distance", "0.005"], "--distance"),
    (["simulate", "--seed", "-1"], "--seed"),
    (["simulate", "--disturbance", "current:speed=1e308"], "current.speed"),
    (["simulate", "--disturbance", "vibration:torque=1e308,force=1e308"], "vibration.torque"),
    (["simulate", "--disturbance", "occlusion:start=30"], "after the end"),
    (["run", "--noise-scale", "inf"], "--noise-scale"),
    (["run", "--noise-scale", "5e-324"], "--noise-scale"),  # its peak SNR divided by zero
    (["run", "--bit-rate", "5e-324"], "--bit-rate"),  # budget's SNR was infinite
    (["run", "--estimator", "pf", "--particles", "0"], "--particles"),
    (["run", "--estimator", "pf", "--particles", "10000000000000"], "--particles"),
    (["run", "--seeds", "-1"], "--seeds"),
    (["run", "--workers", "0"], "--workers"),
    (["run", "--disturbance", "occlusion:start=11"], "after the end"),
    (["render", "--fps", "inf"], "--fps"),
    (["run", "--depth", "0.5"], "--depth"),
    (["run", "--depth", "nan"], "--depth"),
    (["sweep", "--transmitter-depth", "0"], "--transmitter-depth"),
    (["run", "--transmitter-depth", "100"], "--transmitter-depth"),
    (["run", "--link", "paper", "--disturbance", "flicker"], "physical link"),
    (["evaluate", "--scenario", "if1", "--distance", "inf"], "--distance"),
])
def test_hostile_numbers_are_refused_before_any_work(tmp_path, args, needle):
    out = tmp_path / ("v.mp4" if args[0] == "render" else "out")
    r = run_cli(*args, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists()


def test_train_checks_its_output_before_training(tmp_path):
    for out, needle in ((tmp_path, "is a folder"), (tmp_path / "no" / "x.pt", "does not exist"),
                        (tmp_path / "x.txt", ".pt")):
        r = run_cli("train", "--samples", "1000", "--out", str(out))
        assert_user_error(r, needle)
        assert "trained" not in r.stderr


@pytest.mark.parametrize("spec", ["vibration:frequency=0", "vibration:frequency=51",
                                  "current:gust=-1", "current:hold=0.5", "current:seed=-1",
                                  "transmitter:sway=10", "occlusion:duration=0",
                                  "occlusion:start=-1", "vibration:torque=nan"])
def test_disturbance_keys_have_physical_ranges(spec):
    with pytest.raises(DisturbanceError, match=spec.split(":")[1].split("=")[0]):
        parse_disturbance(spec)


class _Payload:
    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        import os

        return (os.system, (f"touch {self.marker}",))


@pytest.mark.parametrize("protocol", [2, 4])
def test_a_pickle_with_a_payload_is_refused_in_one_line(tmp_path, protocol):
    import pickle

    marker = tmp_path / "pwned"
    evil = tmp_path / "evil.pt"
    evil.write_bytes(pickle.dumps(_Payload(marker), protocol=protocol))
    r = run_cli("evaluate", "--scenario", "if1", "--seeds", "1", "--checkpoint", str(evil),
                "--out", str(tmp_path / "out"))
    assert_user_error(r, "evil.pt")
    assert not marker.exists() and not (tmp_path / "out").exists()


def test_the_scene_needs_room_for_both_housings_but_the_budget_goes_closer():
    """MIN_DISTANCE binds the MuJoCo scene (and the --distance flag), not the radiometry:
    ``ledsim budget`` searches for its range below it."""
    from ledsim.constants import MIN_DISTANCE, LinkConstants
    from ledsim.physics.scene import WorldConfig
    from ledsim.radiometry.budget import budget_report

    with pytest.raises(ValueError, match="constants.distance"):
        WorldConfig(constants=LinkConstants(distance=0.5 * MIN_DISTANCE))
    assert budget_report("luma", attenuation=100.0).range_at_fec_limit_m > 0


@pytest.mark.parametrize("args,needle", [
    (["run", "--disturbance", "bogus\nx", "--out", "o"], "unknown disturbance 'bogus\\nx'"),
    (["run", "--camera\r", "--out", "o"], "--camera\\r"),  # argparse's own message
    (["budget", "--link", "a\u2028b"], "a\\u2028b"),
])
def test_line_breaks_a_user_typed_stay_on_the_one_line_of_the_error(tmp_path, args, needle):
    """Messages quote what the user typed; its line breaks are shown escaped, so that
    an error stays one line (found by the CLI fuzz: ``budget -- --link $'\\r0'``)."""
    r = run_cli(*args, cwd=tmp_path)
    assert_user_error(r, needle)


@pytest.mark.parametrize("flag,needle", [("--torque-limit=--", "'--' is not a number"),
                                         ("--integrator=--", "invalid choice: '--'")])
def test_a_double_dash_given_as_a_value_is_that_value(tmp_path, flag, needle):
    """``--flag=--`` gave the flag an empty list on Python 3.11 (argparse took the "--"
    for the end of the options), and the run failed on it with a TypeError (found by the
    CLI fuzz); the value is "--", refused by the flag's own type or choices."""
    out = tmp_path / "out"
    r = run_cli("simulate", flag, "--out", str(out))
    assert_user_error(r, needle)
    assert not out.exists()


@pytest.mark.parametrize("args,needle", [
    # the receiver's peak SNR 1e-158: the supervisor's noise prior overflowed
    (["--link", "luma", "--attenuation", "16"], "leaves the receiver in the dark"),
    # the LED 3 m under a receiver 1 m deep stood under the scene's seabed (found in the
    # run's first step); the seabed now follows the deeper end, and a --sea-depth above
    # an end is refused
    (["--link", "luma", "--depth", "1", "--transmitter-depth", "4", "--sea-depth", "3"],
     "--sea-depth 3.0 is not allowed"),
])
def test_a_link_no_run_can_use_is_refused_before_it_starts(tmp_path, args, needle):
    """Found by the CLI fuzz running for real; both were failures inside the run."""
    for command in ("run", "sweep"):
        out = tmp_path / command
        r = run_cli(command, *args, "--seeds", "1", "--out", str(out))
        assert_user_error(r, needle)
        assert not out.exists()


def test_a_lost_link_at_twice_its_range_still_runs():
    """The dark-receiver floor leaves the lost links people study: twice the FEC range
    in murky water (peak SNR 2e-4) validates."""
    from ledsim.loop.registry import MIN_RUN_PEAK_SNR, peak_snr
    from ledsim.loop.run_config import RunConfig

    cfg = RunConfig(link="luma", attenuation=16.0, distance=2.08, estimator="ekf")
    cfg.validate()
    assert MIN_RUN_PEAK_SNR < peak_snr(cfg.world_config().constants, 1.0) < 1e-3
