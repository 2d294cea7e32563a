"""LinkAlign-v0's reward is the share of the achievable power: it stays in [0, 1] and the
observations in their space whatever the actions, swimming the vehicle included."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from ledsim.envs import ENV_ID


def _raw_share(env) -> float:
    """The reward before the cut of round-off at 1: power over the achievable power."""
    from ledsim.radiometry.optics import achievable_power

    r = env.reading
    best = achievable_power(r.distance[0], r.emission_angle[0], env.system.constants,
                            env.peak_response)
    return float(r.power_clean[0] / best)


def _episode(env, actions):
    obs, _ = env.reset(seed=0)
    rewards, inside = [], [env.observation_space.contains(obs)]
    for a in actions:
        obs, r, *_ = env.step(np.array([a], np.float32))
        assert -1e-12 <= _raw_share(env) <= 1.0 + 1e-9  # the bound holds before the cut
        rewards.append(r)
        inside.append(env.observation_space.contains(obs))
    return np.array(rewards), np.array(inside)


@pytest.mark.parametrize("frequency", [0.5, 2.0, 8.0, 25.0])
def test_bang_bang_at_any_frequency_stays_in_bounds(frequency):
    env = gym.make(ENV_ID).unwrapped
    t = np.arange(1000) * env.dt
    actions = np.sign(np.sin(2 * np.pi * frequency * t) + 1e-12)
    rewards, inside = _episode(env, actions)
    assert inside.all()
    assert rewards.min() >= 0.0 and rewards.max() <= 1.0
    env.close()


def test_swimming_toward_the_led_earns_nothing():
    # Torquing the gimbal pushes the free vehicle: it drifts, yet the reward counts only
    # the share of what the geometry of the moment allows.
    env = gym.make(ENV_ID).unwrapped
    rng = np.random.default_rng(3)
    rewards, inside = _episode(env, rng.choice([-1.0, 1.0], 1000))
    assert inside.all() and 0.0 <= rewards.min() and rewards.max() <= 1.0
    assert np.linalg.norm(env.world.hull_pos - env.world.initial_hull_pos) > 1e-4


def test_a_short_ppo_run_stays_in_bounds():
    sb3 = pytest.importorskip("stable_baselines3")
    from gymnasium.wrappers import FrameStackObservation

    env = FrameStackObservation(gym.make(ENV_ID), 4)
    model = sb3.PPO("MlpPolicy", env, n_steps=512, batch_size=128, n_epochs=2, seed=0,
                    device="cpu", verbose=0)
    model.set_logger(sb3.common.logger.Logger(None, []))  # no stray log folder in /tmp
    seen = []

    class Watch(sb3.common.callbacks.BaseCallback):
        def _on_step(self) -> bool:
            seen.extend(np.ravel(self.locals["rewards"]).tolist())
            return True

    model.learn(2048, callback=Watch())
    assert len(seen) == 2048 and min(seen) >= 0.0 and max(seen) <= 1.0
