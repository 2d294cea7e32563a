"""The Gymnasium environment: API conformance, rendering, seeding, and the shipped policy."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import ledsim.envs
from ledsim.envs import ENV_ID, EstimatorObservation, ShippedAlignmentPolicy


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID, render_mode="rgb_array", width=160, height=120)
    yield e
    e.close()


def test_passes_gymnasiums_env_checker(env):
    check_env(env.unwrapped, skip_render_check=False)


def test_rgb_array_frames(env):
    env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8 and frame.std() > 5


def test_same_seed_same_episode():
    def episode(seed):
        e = gym.make(ENV_ID, disturbances=("vibration:frequency=3",))
        obs, _ = e.reset(seed=seed)
        out = [obs]
        for k in range(50):
            out.append(e.step(np.array([0.3 * np.sin(k / 5)], np.float32))[0])
        return np.array(out)

    a, b, c = episode(4), episode(4), episode(5)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_every_knob_is_a_constructor_argument():
    e = gym.make(ENV_ID, distance=0.1, noise_scale=2.0, torque_limit=0.02, frame_skip=10,
                 disturbances=("current:speed=0.1",), integrator="euler").unwrapped
    assert e.world.config.integrator == "euler"
    assert e.system.constants.distance == 0.1 and e.system.constants.Te == pytest.approx(0.02)
    assert e.world.config.torque_limit == 0.02 and e.metadata["render_fps"] == 50
    e.reset(seed=0)
    assert e.sensor.noise_std == pytest.approx(2.0 * e.system.constants.measurement_noise_std)


def test_shipped_kkl_and_controller_hold_the_link_as_a_policy():
    env = gym.make(ENV_ID)
    policy = ShippedAlignmentPolicy(env.unwrapped)
    obs, _ = env.reset(seed=0)
    total, steps, truncated, rewards = 0.0, 0, False, []
    while not truncated:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total += reward
        steps += 1
        rewards.append(reward)
    assert steps == 1000 and not terminated
    assert total > 900  # 1000 would be the peak power at every step
    # The link held over the last 2 s: at least 95 % of the power the geometry allows
    # (the station-keeping hull moves phi by a few 0.01 rad; the gimbal follows).
    assert np.mean(rewards[-200:]) > 0.95


def test_estimator_wrapper_adds_the_estimate():
    env = EstimatorObservation(gym.make(ENV_ID), estimator="ekf")
    obs, _ = env.reset(seed=0)
    # powers, the vehicle's 5 readings, then the estimate
    assert obs.shape == (9,) and env.observation_space.contains(obs)
    obs, *_ = env.step(np.zeros(1, np.float32))
    assert np.all(np.isfinite(obs))
    bare = EstimatorObservation(gym.make(ENV_ID, imu=False), estimator="ekf")
    assert bare.reset(seed=0)[0].shape == (4,)
    assert ledsim.envs.ENV_ID in gym.registry



def test_estimator_wrapper_adds_a_lost_flag_that_a_kick_raises():
    env = EstimatorObservation(gym.make(ENV_ID, disturbances=("kick:start=1.5",)),
                               estimator="ekf", lost_flag=True)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (10,) and env.observation_space.contains(obs)
    flags = []
    for _ in range(300):  # 3 s, holding still: the kick at 1.5 s throws the link out
        obs, *_ = env.step(np.zeros(1, np.float32))
        flags.append(obs[-1])
    flags = np.array(flags)
    assert set(flags) <= {0.0, 1.0}
    assert not flags[100:150].any() and flags[150:].any()
    env.close()


def test_the_shipped_policy_is_ledsim_runs_stack(tmp_path):
    """reset(seed=K) starts as seed K of ``ledsim run --scenario align`` and the shipped
    policy then acts as ``ledsim run --estimator kkl`` (supervision, bank, scan): the
    trace that ``--save-trace`` writes is the episode's, to 1e-9."""
    from conftest import run_cli

    dist = "vibration:frequency=3,torque=0.3"
    r = run_cli("run", "--link", "paper", "--scenario", "align", "--estimator", "kkl",
                "--disturbance", dist,
                "--seeds", "2", "--workers", "1", "--seconds", "6", "--no-plot", "-q",
                "--save-trace", "--out", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    trace = np.load(tmp_path / "o" / "trace_seed1.npz")
    series = {"t", "phi", "phidot", "phi_hat", "phidot_hat", "p1", "p2", "torque", "lost"}
    assert series <= set(trace.files)  # and what the estimator was given (replay)
    assert all(trace[k].ndim == 1 and len(trace[k]) == 600 for k in series)
    env = gym.make(ENV_ID, scenario="align", disturbances=[dist])
    policy = ShippedAlignmentPolicy(env.unwrapped)
    obs, info = env.reset(seed=1)
    phi, p1, lost = [info["phi"]], [obs[0]], []
    for _ in range(599):
        obs, _, _, _, info = env.step(policy(obs))
        lost.append(policy.lost)
        phi.append(info["phi"])
        p1.append(obs[0])
    np.testing.assert_allclose(phi, trace["phi"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(p1, trace["p1"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(lost, trace["lost"][:599])
    # The policy restarts with the next episode by itself.
    obs, info = env.reset(seed=1)
    assert policy(obs).shape == (1,) and policy.step.decision is not None
    env.close()


@pytest.mark.parametrize("action", [np.array([np.nan]), np.array([0.1, 0.2]),
                                    np.array([np.inf])])
def test_a_bad_action_is_refused_in_one_line(action):
    env = gym.make(ENV_ID).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match="one finite number"):
        env.step(action)


def test_the_env_pickles_as_its_arguments():
    import pickle

    env = gym.make(ENV_ID, scenario="align", disturbances="vibration:frequency=3").unwrapped
    copy = pickle.loads(pickle.dumps(env))
    assert copy.cfg == env.cfg and copy.cfg.disturbances == ("vibration:frequency=3",)
    a, _ = env.reset(seed=3)
    b, _ = copy.reset(seed=3)
    np.testing.assert_array_equal(a, b)


def test_the_estimator_wrapper_passes_gymnasiums_checker():
    import warnings

    env = EstimatorObservation(gym.make(ENV_ID), estimator="ekf", lost_flag=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
    assert not [w for w in caught if "infinity" in str(w.message)]
    env.close()


def test_making_v0_and_v1_says_nothing_of_an_out_of_date_version():
    """The three ids are different tasks: Gymnasium's "out of date" warning for v0 and v1
    (it reads them as v2's releases) is silenced, with every other warning kept."""
    import subprocess
    import sys

    code = ("import gymnasium as gym, ledsim.envs, warnings\n"
            "for i in ('ledsim/LinkAlign-v0', 'ledsim/LinkAlign-v1'):\n"
            "    gym.make(i).close()\n"
            "warnings.warn('kept', DeprecationWarning)\n")
    r = subprocess.run([sys.executable, "-W", "default", "-c", code], capture_output=True,
                       text=True, check=True, env={**__import__("os").environ,
                                                   "MUJOCO_GL": "osmesa"})
    assert "out of date" not in r.stderr, r.stderr
    assert "kept" in r.stderr
