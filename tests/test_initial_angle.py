"""A start that the user chooses: ``--initial-angle`` on run, render and sweep, and
``options={"initial_angle": ...}`` in the env's reset."""

import gymnasium as gym
import numpy as np
import pytest
from conftest import assert_user_error, run_cli

import ledsim.envs  # noqa: F401 (registers the env)
from ledsim.cli.parser import build_parser
from ledsim.errors import LedsimError
from ledsim.loop.closed_loop import run_once
from ledsim.loop.run_config import RunConfig


def test_the_config_starts_where_it_is_told():
    assert RunConfig().scenario_spec.x0 == (0.3, 0.0)
    assert RunConfig(initial_angle=-0.45).scenario_spec.x0 == (-0.45, 0.0)
    assert RunConfig(scenario="if2", initial_angle=0.2).scenario_spec.x0 == (0.2, 0.0)
    with pytest.raises(LedsimError, match="--initial-angle 2.0 is not allowed"):
        RunConfig(initial_angle=2.0).validate()


def test_a_run_starts_at_the_initial_angle():
    s = run_once(RunConfig(estimator="oracle", seconds=0.1, initial_angle=-0.45), 0,
                 keep_trace=True).trace.series()
    assert s["phi"][0] == pytest.approx(-0.45, abs=1e-12)
    assert s["phidot"][0] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("command", [["run"], ["render"], ["sweep"]])
def test_run_render_and_sweep_take_the_flag(command):
    args = build_parser().parse_args(command + ["--initial-angle", "1.0", "--out", "x"])
    assert args.initial_angle == 1.0
    assert build_parser().parse_args(command + ["--out", "x"]).initial_angle is None


@pytest.mark.parametrize("value, needle", [("2", "must be in [-1.4, 1.4] rad"),
                                           ("nan", "must be finite"),
                                           ("left", "is not a number")])
def test_a_bad_initial_angle_is_refused_in_one_line(tmp_path, value, needle):
    r = run_cli("run", "--initial-angle", value, "--out", str(tmp_path / "o"))
    assert_user_error(r, needle)


def test_the_env_starts_at_the_option():
    env = gym.make("ledsim/LinkAlign-v0", scenario="align", imu=False)
    try:
        _, info = env.reset(seed=3, options={"initial_angle": 1.0})
        assert info["phi"] == pytest.approx(1.0, abs=1e-12)
        _, info = env.reset(seed=3)
        assert info["phi"] == pytest.approx(0.3, abs=1e-12)
        for bad in ("x", np.inf, -1.5):
            with pytest.raises(ValueError, match="initial_angle .* is not allowed"):
                env.reset(options={"initial_angle": bad})
    finally:
        env.close()
