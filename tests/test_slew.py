"""Acquisition at the torque limit: the beam fixed from the pair of powers, a
near-minimum-time slew on the encoder, and the hand-over to tracking."""

import math

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.agent.laws import intensity_maximum
from ledsim.agent.slew import BeamFix, TimeOptimalSlew
from ledsim.constants import LinkConstants
from ledsim.loop.closed_loop import run_once
from ledsim.loop.run_config import RunConfig
from ledsim.radiometry.optics import layout_power

C = LinkConstants()
INERTIA, LIMIT = 2.09e-4, 0.05  # the shipped gimbal's [kg m^2], [N m]


def slew_on_an_inertia(target: float, steps: int = 40, substeps: int = 5):
    """Encoder angle and rate of a pure inertia under the slew, at 100 Hz (torque held
    over each control period, integrated in ``substeps``)."""
    slew = TimeOptimalSlew(INERTIA, LIMIT, C.Te)
    q, v, path = 0.0, 0.0, []
    for _ in range(steps):
        u = slew.command(q, v, target)  # phi'' = -q''
        assert abs(u) <= LIMIT / INERTIA
        h = C.Te / substeps
        for _ in range(substeps):
            v -= u * h
            q += v * h
        path.append((q, v))
    return np.array(path)


@pytest.mark.parametrize("target", [0.3, -0.45, 0.05])
def test_the_slew_is_near_minimum_time_without_overshoot(target):
    path = slew_on_an_inertia(target)
    bound = 2 * math.sqrt(abs(target) / (LIMIT / INERTIA))  # bang-bang [s]
    arrived = np.flatnonzero(np.abs(path[:, 0] - target) < 0.005)[0]
    assert (arrived + 1) * C.Te <= bound + 0.06
    assert np.max(np.sign(target) * (path[:, 0] - target)) < 0.005  # no overshoot
    assert abs(path[-1, 0] - target) < 1e-3 and abs(path[-1, 1]) < 0.05


def test_the_fix_finds_the_beam_from_noisy_pairs_and_ignores_darkness():
    phi_ref = intensity_maximum(C)
    fix = BeamFix(C, phi_ref)
    rng = np.random.default_rng(0)
    sigma = C.measurement_noise_std
    assert not fix.add([0.01, -0.02], 0.0, sigma)  # in the noise
    assert not fix.add([np.nan, 0.5], 0.0, sigma)  # gated out
    assert fix.target is None and fix.stderr == math.inf
    # The gimbal moves; the beam stays: phi_k = phi_home - q_k with phi_home = 0.3.
    for q in np.linspace(0.0, 0.25, 20):
        y = layout_power(0.9, 0.3 - q, C) + sigma * rng.standard_normal(2)
        assert fix.add(y, q, sigma)
    assert fix.stderr < 0.01
    assert abs(fix.target - (0.3 - phi_ref)) < 4 * fix.stderr
    assert fix.gain == pytest.approx(0.9, rel=0.05)


def test_minimum_time_acquisition_aligns_in_a_fraction_of_a_second():
    kkl = run_once(RunConfig(seconds=2.0), 0).metrics  # minimum-time: the default
    assert kkl.alignment_time is not None and kkl.alignment_time < 0.25
    assert kkl.silent_error_share == 0.0
    warm = run_once(RunConfig(acquisition="warm-up", seconds=2.0), 0).metrics
    assert warm.alignment_time is None or warm.alignment_time > 1.0  # the warm-up's 1 s
    oracle = run_once(RunConfig(estimator="oracle", acquisition="minimum-time",
                                seconds=2.0), 0).metrics
    assert oracle.alignment_time < 0.15


def test_a_kicked_gimbal_is_back_within_a_quarter_second():
    m = run_once(RunConfig(acquisition="minimum-time", seconds=3.0,
                           disturbances=("kick:start=1.5,rate=12",)), 1).metrics
    assert m.recovery_time is not None and m.recovery_time < 0.25


def test_out_of_view_the_scan_finds_the_beam():
    m = run_once(RunConfig(acquisition="minimum-time", seconds=3.0, initial_angle=1.0),
                 0).metrics
    assert m.alignment_time is not None and m.alignment_time < 1.5


def test_a_bad_acquisition_is_refused_in_one_line(tmp_path):
    assert_user_error(run_cli("run", "--acquisition", "instant", "--out",
                              str(tmp_path / "o")), "instant")


def test_the_envs_shipped_policy_takes_the_acquisition():
    import gymnasium as gym

    import ledsim.envs  # noqa: F401
    from ledsim.envs import ShippedAlignmentPolicy

    shares = {}
    for acq in ("warm-up", "minimum-time"):
        env = gym.make("ledsim/LinkAlign-v0", scenario="align", acquisition=acq,
                       max_episode_steps=200)
        try:
            policy = ShippedAlignmentPolicy(env.unwrapped, "kkl")
            obs, _ = env.reset(seed=100)
            rewards, done = [], False
            while not done:
                obs, r, term, trunc, _ = env.step(policy(obs))
                rewards.append(r)
                done = term or trunc
        finally:
            env.close()
        shares[acq] = np.mean(np.array(rewards) >= 0.9)
    assert shares["minimum-time"] > 0.9 > 0.5 > shares["warm-up"]


def test_weak_light_still_hands_over_to_the_estimator():
    """Where the light is too weak for the fix to reach its hand-over error within its
    memory (0.12 m), the acquisition hands over after one memory at the target instead
    of holding the link in 'acquiring' for good."""
    m = run_once(RunConfig(acquisition="minimum-time", distance=0.12, seconds=3.0), 7).metrics
    assert m.lost_share < 0.3
    assert m.availability > 0.9


def test_a_link_too_weak_for_the_fix_acquires_with_the_warm_up(tmp_path):
    from ledsim.loop.registry import MIN_FAST_PEAK_SNR, peak_snr

    near, far = RunConfig(distance=0.25), RunConfig(distance=0.3)
    assert peak_snr(far.world_config().constants, 1.0) < MIN_FAST_PEAK_SNR
    assert near.fast_acquisition and not far.fast_acquisition
    assert far.scenario_spec.warmup == 1.0 and near.scenario_spec.warmup == 0.0
    assert RunConfig(distance=0.3, estimator="oracle").fast_acquisition  # needs no light
    assert not RunConfig(noise_scale=10.0).fast_acquisition
    r = run_cli("run", "--link", "paper", "--distance", "0.3", "--seconds", "0.2", "--seeds", "1",
                "--no-plot", "--out", str(tmp_path / "o"), "-q")
    assert r.returncode == 0 and "acquires with the warm-up" in r.stderr, r.stderr
