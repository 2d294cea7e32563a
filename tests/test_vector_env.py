"""The native vector env: ``gym.make_vec`` builds it, each sub-environment is the single
env of its seed bit for bit, both autoreset modes keep Gymnasium's contract, and
stable-baselines3 trains on it through the adapter."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import ledsim.envs  # noqa: F401 (registers the ids)
from ledsim.envs.vector import LinkAlignVectorEnv

warnings.filterwarnings("ignore", message=".*out of date.*")
ENV = "ledsim/LinkAlign-v0"


def _single_run(seed, actions, **kw):
    env = gym.make(ENV, **kw)
    obs, _ = env.reset(seed=seed)
    out, rewards, infos = [obs], [], []
    for a in actions:
        obs, r, _, _, info = env.step(a)
        out.append(obs)
        rewards.append(r)
        infos.append(info)
    env.close()
    return np.array(out), np.array(rewards), infos


@pytest.mark.parametrize("kw", [
    dict(disturbances=("current:speed=0.05,gust=0.02",)),
    dict(disturbances=("vibration:frequency=3,torque=0.5",), scenario=None),
    dict(imu=False, distance=3.0),
], ids=["current", "vibration-random-start", "no-imu"])
@pytest.mark.parametrize("n", [1, 3])
def test_each_sub_env_is_the_single_env_of_its_seed(kw, n):
    venv = gym.make_vec(ENV, num_envs=n, threads=2 if n > 1 else 1, **kw)
    assert isinstance(venv.unwrapped, LinkAlignVectorEnv)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (25, n, 1)).astype(np.float32)
    obs, _ = venv.reset(seed=11)
    seen, rewards, infos = [obs], [], []
    for a in actions:
        obs, r, term, trunc, info = venv.step(a)
        assert not term.any() and not trunc.any()
        assert set(info) >= {"phi", "_phi", "power_clean", "time"}
        seen.append(obs)
        rewards.append(r)
        infos.append(info)
    venv.close()
    seen, rewards = np.array(seen), np.array(rewards)
    for i in range(n):
        obs_i, rew_i, info_i = _single_run(11 + i, actions[:, i], **kw)
        np.testing.assert_array_equal(seen[:, i], obs_i, err_msg=f"sub-env {i}")
        np.testing.assert_array_equal(rewards[:, i], rew_i, err_msg=f"sub-env {i}")
        for key in ("phi", "phidot", "power_clean", "time"):
            np.testing.assert_array_equal([info[key][i] for info in infos],
                                          [info[key] for info in info_i],
                                          err_msg=f"sub-env {i}: info {key!r}")


def test_the_rows_reward_is_the_single_envs_to_the_bit():
    """The reward's achievable power over rows against the single env's, one at a time,
    at random distances and LED angles (numpy's scalars and arrays round differently)."""
    from ledsim.envs.observe_rows import _achievable
    from ledsim.radiometry.optics import achievable_power

    env = gym.make(ENV).unwrapped
    c, peak = env.system.constants, env.peak_response
    rng = np.random.default_rng(3)
    d, theta = rng.uniform(0.05, 40.0, 4000), rng.uniform(-2.0, 2.0, 4000)
    one = [float(achievable_power(di, ti, c, peak)) for di, ti in zip(d, theta, strict=True)]
    np.testing.assert_array_equal(_achievable(d, theta, c, peak), one)
    env.close()


def test_next_step_autoreset_resets_the_step_after_the_episode_ends():
    venv = gym.make_vec(ENV, num_envs=2, max_episode_steps=3)
    assert venv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    venv.reset(seed=0)
    a = np.zeros((2, 1), np.float32)
    for _ in range(2):
        _, _, _, trunc, _ = venv.step(a)
        assert not trunc.any()
    _, _, _, trunc, info = venv.step(a)
    assert trunc.all()
    keys = list(info)
    obs, reward, term, trunc, info = venv.step(a)  # the reset step
    assert list(info) == keys  # each key then its mask, whichever path stacked them
    assert not trunc.any() and not term.any() and (reward == 0).all()
    assert (info["time"] == 0).all()  # a new episode's first observation
    _, _, _, trunc, info = venv.step(a)
    assert not trunc.any() and np.allclose(info["time"], 0.01)
    venv.close()


def test_same_step_autoreset_returns_the_new_episode_and_keeps_the_last_observation():
    venv = gym.make_vec(ENV, num_envs=2, max_episode_steps=2, autoreset_mode="same-step")
    assert venv.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    venv.reset(seed=0)
    a = np.zeros((2, 1), np.float32)
    venv.step(a)
    obs, reward, _, trunc, info = venv.step(a)
    assert trunc.all() and info["_final_obs"].all()
    assert (info["time"] == 0).all()  # the returned observation starts the next episode
    assert info["final_info"][0]["time"] == pytest.approx(0.02)
    assert not np.array_equal(info["final_obs"][0], obs[0])
    venv.close()


@pytest.mark.parametrize("kw,needle", [
    (dict(num_envs=0), "num_envs 0"),
    (dict(num_envs=2, autoreset_mode="sometimes"), "autoreset_mode 'sometimes'"),
    (dict(num_envs=2, render_mode="rgb_array"), "render_mode 'rgb_array'"),
    (dict(num_envs=2, max_episode_steps=0), "max_episode_steps 0"),
])
def test_bad_arguments_are_refused(kw, needle):
    with pytest.raises(ValueError, match=needle):
        LinkAlignVectorEnv(**kw)


def test_actions_of_the_wrong_shape_are_refused():
    venv = LinkAlignVectorEnv(num_envs=2)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="one row per sub-environment"):
        venv.step(np.zeros((3, 1)))
    k = [e.k for e in venv.envs]
    with pytest.raises(ValueError, match="not allowed: one finite number"):
        venv.step(np.array([[0.1], [np.nan]]))  # the batch's check hands it to the env
    assert [e.k for e in venv.envs] == k  # refused before any env was commanded
    venv.close()


def test_sync_and_async_stay_available():
    venv = gym.make_vec(ENV, num_envs=2, vectorization_mode="sync")
    assert type(venv).__name__ == "SyncVectorEnv"
    venv.close()


def test_stable_baselines3_trains_ppo_through_the_adapter():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import Logger
    from stable_baselines3.common.vec_env import VecFrameStack

    from ledsim.envs.sb3 import VectorEnvForSB3, make_sb3_vec_env

    with pytest.raises(ValueError, match="same-step"):
        VectorEnvForSB3(gym.make_vec(ENV, num_envs=2))
    venv = make_sb3_vec_env(ENV, num_envs=4, scenario=None, max_episode_steps=50)
    model = PPO("MlpPolicy", VecFrameStack(venv, 2), n_steps=32, batch_size=64, seed=0,
                device="cpu")
    model.set_logger(Logger(None, []))  # no stray log folder in /tmp
    model.learn(256)
    obs = venv.reset()
    for k in range(50):
        obs, reward, dones, infos = venv.step(np.zeros((4, 1), np.float32))
        assert ((0 <= reward) & (reward <= 1)).all()
        assert dones.all() == (k == 49)  # the time limit, on the 50th step
    assert all(i["TimeLimit.truncated"] and i["terminal_observation"].shape == (7,)
               for i in infos)
    venv.close()
