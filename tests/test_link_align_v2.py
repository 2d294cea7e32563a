"""``ledsim/LinkAlign-v2``: the pan-tilt head's env (issue 48), checked by Gymnasium's and
Stable-Baselines3's own env checkers; its powers on the link's scale."""

import warnings

import gymnasium as gym
import numpy as np
import pytest

import ledsim.envs  # noqa: F401 (registers the ids)
from ledsim.loop.closed_loop import ClosedLoop
from ledsim.loop.run_config import RunSpec


@pytest.fixture(scope="module")
def env():
    e = gym.make("ledsim/LinkAlign-v2", scenario="align")
    yield e
    e.close()


def test_the_checkers_of_gymnasium_and_stable_baselines3_pass(env):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped, skip_render_check=True)
        sb3_check(env.unwrapped, warn=False)


def test_two_torques_out_five_powers_on_the_links_scale_and_both_encoders_in(env):
    assert env.action_space.shape == (2,)
    assert env.observation_space.shape == (10,)
    obs, info = env.reset(seed=0)
    powers = obs[:5]
    # the data detector 0.3 rad off: about 0.8 of its peak (LinkAlign-v1 reads 2e-8 W)
    assert 0.5 < powers[0] < 1.0 and np.all(powers > 0.3), powers
    high = env.observation_space.high[:5]
    assert np.all(high < 5), high  # a span an agent can scale by (v1: 2.29 W)
    np.testing.assert_allclose(info["x"][:2], [0.3, 0.0], atol=1e-3)
    obs, reward, *_ = env.step(np.array([0.5, -0.5], dtype=np.float32))
    assert env.observation_space.contains(obs) and 0.0 <= reward <= 1.0


def test_an_episode_starts_where_the_run_of_its_seed_starts(env):
    spec = RunSpec(link="luma", gimbal="pan-tilt", seconds=0.05)
    run = ClosedLoop(spec, [7]).runs[0]
    _, info = env.reset(seed=7)
    np.testing.assert_allclose(info["x"], run.sensor.read(noise=False).x, atol=1e-12)


def test_a_yaw_gimbal_is_not_this_env():
    with pytest.raises(ValueError, match="LinkAlign-v2 is the pan-tilt head's"):
        gym.make("ledsim/LinkAlign-v2", gimbal="yaw")
