"""stable-baselines3 on a Gymnasium vector env: :class:`VectorEnvForSB3`.

stable-baselines3 trains on its own ``VecEnv`` type, not on Gymnasium's ``VectorEnv``.
The adapter gives it the native :class:`~ledsim.envs.vector.LinkAlignVectorEnv` (or
any Gymnasium vector env in ``same-step`` autoreset mode, stable-baselines3's own):
``dones`` is terminated or truncated, and a finished episode's last observation is
``infos[i]["terminal_observation"]``, with ``"TimeLimit.truncated"`` set when it was cut
by the time limit. Needs the ``rl`` extra (``pip install 'ledsim[rl]'``).

    from ledsim.envs.sb3 import make_sb3_vec_env
    from stable_baselines3 import PPO
    venv = make_sb3_vec_env("ledsim/LinkAlign-v0", num_envs=16, scenario=None)
    PPO("MlpPolicy", venv).learn(100_000)
"""

from __future__ import annotations

import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper


class VectorEnvForSB3(VecEnv):
    """A Gymnasium vector env in ``same-step`` autoreset mode as stable-baselines3's
    ``VecEnv`` (see the module docstring).

    Args:
        env: the vector env; its ``metadata["autoreset_mode"]`` must be ``SAME_STEP``.
    """

    def __init__(self, env):
        mode = env.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"autoreset_mode {mode!r} is not allowed: stable-baselines3 "
                             "needs 'same-step' (make_vec(..., autoreset_mode='same-step'))")
        self.env = env
        super().__init__(env.num_envs, env.single_observation_space,
                         env.single_action_space)
        self._actions = None
        self._seed = None
        self._options = None

    def reset(self) -> np.ndarray:
        obs, _ = self.env.reset(seed=self._seed, options=self._options)
        self._seed = None  # seeded once, as stable-baselines3's own VecEnvs do
        return obs

    def seed(self, seed: int | None = None):
        self._seed = seed
        return [None if seed is None else seed + i for i in range(self.num_envs)]

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        obs, reward, terminated, truncated, info = self.env.step(self._actions)
        dones = terminated | truncated
        infos = [{} for _ in range(self.num_envs)]
        final = info.get("_final_obs", np.zeros(self.num_envs, dtype=bool))
        for i in np.flatnonzero(dones):
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            if final[i]:
                infos[i]["terminal_observation"] = info["final_obs"][i]
        return obs, reward.astype(np.float32), dones, infos

    def close(self) -> None:
        self.env.close()

    def _targets(self, indices) -> list:
        return [self.env.envs[i] for i in self._get_indices(indices)]

    def get_attr(self, attr_name: str, indices=None) -> list:
        return [getattr(e, attr_name) for e in self._targets(indices)]

    def set_attr(self, attr_name: str, value, indices=None) -> None:
        for e in self._targets(indices):
            setattr(e, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs):
        return [getattr(e, method_name)(*method_args, **method_kwargs)
                for e in self._targets(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False] * len(self._get_indices(indices))


class EpisodeRecord(VecEnvWrapper):
    """Records each finished episode's return and length, as stable-baselines3's
    ``Monitor`` does for one env (``get_episode_rewards``, ``get_episode_lengths``)."""

    def __init__(self, venv):
        super().__init__(venv)
        self.returns, self.lengths = np.zeros(venv.num_envs), np.zeros(venv.num_envs, int)
        self.done_returns: list[float] = []
        self.done_lengths: list[int] = []

    def reset(self):
        self.returns[:], self.lengths[:] = 0.0, 0
        return self.venv.reset()

    def step_wait(self):
        obs, rew, dones, infos = self.venv.step_wait()
        self.returns += rew
        self.lengths += 1
        for i in np.flatnonzero(dones):
            self.done_returns.append(float(self.returns[i]))
            self.done_lengths.append(int(self.lengths[i]))
            self.returns[i], self.lengths[i] = 0.0, 0
        return obs, rew, dones, infos

    def get_episode_lengths(self) -> list[int]:
        return self.done_lengths

    def get_episode_rewards(self) -> list[float]:
        return self.done_returns


def make_sb3_vec_env(env_id: str = "ledsim/LinkAlign-v0", num_envs: int = 8,
                     **kwargs) -> VectorEnvForSB3:
    """The native vector env of ``env_id`` with ``num_envs`` worlds (``kwargs``: the
    env's constructor arguments, and ``threads``) for stable-baselines3."""
    import gymnasium as gym

    import ledsim.envs  # noqa: F401 (registers the ids)

    return VectorEnvForSB3(gym.make_vec(env_id, num_envs=num_envs,
                                        vectorization_mode="vector_entry_point",
                                        autoreset_mode="same-step", **kwargs))
